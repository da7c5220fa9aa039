"""sawdds.record: writes every sample of some topics to an MCAP file (the ROS 2 message schemas,
CDR as it came over the wire: what ROS 2 bags and Foxglove open) and to one CSV file per topic,
in a process of its own, counting what it missed.

Its readers keep every sample until taken (KEEP_ALL): none is overwritten while the recorder is
busy. What DDS itself lost on the way (a best-effort sample that never arrived: a gap in the
writer's sequence numbers) is counted by Cyclone DDS as "sample lost", and a sample the reader
refused for want of resources as "sample rejected"; both are in the summary, with the longest
silence between two samples of each topic. A state topic is also checked against the RT task's
own cycle counter: its component's period_statistics is recorded alongside (added if not named),
and the rows the task ran that never reached the recording are counted ("upstream_missed").

usage: python -m sawdds.record --domain N --out DIR --topic rt/... [--topic ...] [--seconds S]
Prints "ready" once every topic's reader has matched its gateway's writer, and on SIGINT,
SIGTERM or after S seconds one JSON line: {"files": [...], "topics": {topic: {"samples",
"lost", "rejected", "longest_gap_s"}}}. Exit 1 with one line if a topic cannot be recorded.
"""
import argparse
import array
import csv
import faulthandler
import json
import os
import signal
import sys
import time

from cyclonedds._clayer import ddspy_take
from cyclonedds.core import InstanceState, Policy, Qos, SampleState, ViewState
from cyclonedds.sub import DataReader

from .client import XCDR1, Client, latched
from . import cdr, msgs, values

ANY = SampleState.Any | ViewState.Any | InstanceState.Any


def ros_topic(dds_topic: str) -> str:
    """The ROS 2 name of a DDS topic ("rt/saw/x" -> "/saw/x"), as a ROS 2 bag names it."""
    return "/" + dds_topic[3:] if dds_topic.startswith("rt/") else dds_topic


class Track:
    """One recorded topic: its reader, MCAP channel and CSV file, and what it counted."""

    def __init__(self, client, endpoint, mcap_writer, schemas, directory):
        self.topic, self.endpoint = endpoint.topic, endpoint
        self.cls = msgs.BY_DDS_NAME[endpoint.dds_type]
        reliable = latched(endpoint) or endpoint.kind.endswith("event")
        qos = Qos(Policy.Reliability.Reliable(0) if reliable else Policy.Reliability.BestEffort,
                  Policy.Durability.TransientLocal if latched(endpoint) else Policy.Durability.Volatile,
                  Policy.History.KeepAll, XCDR1)
        self.reader = DataReader(client.participant, client._topic(self.topic, self.cls), qos=qos)
        name = cdr.ros_name(self.cls)
        if name not in schemas:
            schemas[name] = mcap_writer.register_schema(name=name, encoding="ros2msg",
                                                        data=cdr.ros2msg(self.cls).encode())
        self.channel = mcap_writer.register_channel(topic=ros_topic(self.topic), message_encoding="cdr",
                                                    schema_id=schemas[name], metadata={"dds_topic": self.topic})
        self.csv_path = os.path.join(directory, self.topic.replace("/", "_") + ".csv")
        self.csv_file = open(self.csv_path, "w", newline="")
        self.csv = csv.writer(self.csv_file)
        self.names, self.layout = None, None
        self.samples, self.last_time, self.longest_gap = 0, None, 0.0
        self.stamps = array.array("q")  # every sample's source time (ns): checked against the task's cycles
        self.cycles = []  # (source time ns, cycles) of a period_statistics topic (first and last)

    def take(self, mcap_writer):
        got = ddspy_take(self.reader._ref, ANY, 4096)
        if isinstance(got, int):
            return 0
        batch = [(d, i.source_timestamp) for d, i in got if i.valid_data]
        if not batch:
            return 0
        now = time.time_ns()
        for d, ts in batch:
            self.samples += 1
            mcap_writer.add_message(self.channel, log_time=now, data=d, publish_time=ts, sequence=self.samples)
        self.stamps.extend(ts for _, ts in batch)
        if self.cls is msgs.TaskStatistics:
            for d, ts in (batch[0], batch[-1]):
                self.cycles[1 if self.cycles else 0:] = [(ts, self.cls.deserialize(d).cycles)]
        times = [ts * 1e-9 for _, ts in batch]
        for t in times:
            if self.last_time is not None:
                self.longest_gap = max(self.longest_gap, t - self.last_time)
            self.last_time = t
        self._csv(batch, times)
        return len(batch)

    def _csv(self, batch, times):
        datas = [d for d, _ in batch]
        if self.names is None:
            first = self.cls.deserialize(datas[0])
            self.names = list(values.numbers(first))
            text = not self.names
            self.csv.writerow(["source_time_s"] + (["text"] if text else self.names))
            try:
                self.layout = cdr.Layout(self.cls, datas[0], self.names) if self.names else None
            except (TypeError, ValueError):
                self.layout = None
        decoded = self.layout.decode(datas) if self.layout is not None else None
        if decoded is not None:
            self.csv.writerows([f"{t:.6f}"] + [f"{x:.17g}" for x in row] for t, row in zip(times, decoded[0]))
            return
        for d, t in zip(datas, times):
            s = self.cls.deserialize(d)
            if self.names:
                nums = values.numbers(s)
                self.csv.writerow([f"{t:.6f}"] + [nums.get(n, "") for n in self.names])
            else:
                self.csv.writerow([f"{t:.6f}", values.text(s)])

    def summary(self, statistics=None):
        """What was recorded and missed. With `statistics` (the Track of the same component's
        period_statistics, recorded alongside), a state topic published every cycle is also checked
        against the RT task's own cycle counter: between its first and last statistics sample the
        task ran `rt_rows` cycles, each a row with this topic's value; `upstream_missed` of them
        never reached the recording (the gateway reads the newest row: one it was too late for is
        not published)."""
        lost = self.reader.get_sample_lost_status().total_count
        rejected = self.reader.get_sample_rejected_status().total_count
        out = {"samples": self.samples, "lost": lost, "rejected": rejected, "missed": lost + rejected,
               "longest_gap_s": round(self.longest_gap, 6), "csv": self.csv_path}
        if statistics is not None and len(statistics.cycles) == 2 and statistics is not self:
            (ta, ca), (tb, cb) = statistics.cycles
            rows = sum(1 for t in self.stamps if ta < t <= tb)
            out.update(rt_rows=cb - ca, rows_between=rows, upstream_missed=max(0, cb - ca - rows),
                       rt_window_ns=[ta, tb])
            out["missed"] += out["upstream_missed"]
        return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m sawdds.record", description=__doc__.split("\n\n")[0])
    p.add_argument("--domain", type=int, default=0)
    p.add_argument("--out", required=True, help="directory for recording.mcap and the CSV files")
    p.add_argument("--topic", action="append", required=True, help="a DDS topic (rt/...) to record")
    p.add_argument("--seconds", type=float, help="stop after this long (default: at SIGINT or SIGTERM)")
    p.add_argument("--wait", type=float, default=10.0, help="how long to look for the topics' gateways")
    args = p.parse_args(argv)
    from mcap.writer import CompressionType, Writer
    # A stop is a plain flag: a handler that took a lock (Event.set) could find it held by the
    # very thread it interrupts (inside Event.wait) and never return. SIGUSR1 prints where every
    # thread is (faulthandler, from C): what a caller asks before it kills a recorder that hangs.
    stop = [False]

    def stopping(*_):
        stop[0] = True
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, stopping)
    faulthandler.register(signal.SIGUSR1, all_threads=True)
    os.makedirs(args.out, exist_ok=True)
    client = Client(args.domain)
    endpoints = []
    for topic in args.topic:
        try:
            e = client.find(topic, timeout=args.wait)
        except LookupError as why:
            print(f"sawdds.record: {why} (domain {args.domain})", file=sys.stderr)
            return 1
        if e.dds_type not in msgs.BY_DDS_NAME:
            print(f"sawdds.record: {topic}: {e.dds_type} is not a type sawdds knows", file=sys.stderr)
            return 1
        endpoints.append(e)
    # A state topic is checked against its task's cycle counter: the component's period_statistics
    # is recorded too when it has one (and the recording did not name it).
    named = {e.topic for e in endpoints}
    for m in client.manifests(timeout=0).values():
        for e in m.endpoints:
            if (e.name == "period_statistics" and e.kind == "read" and e.topic and e.topic not in named
                    and any(x.component_name == e.component_name and x.kind == "read" for x in endpoints)):
                endpoints.append(e)
                named.add(e.topic)
        mcap_path = os.path.join(args.out, "recording.mcap")
    out = open(mcap_path, "wb")
    writer = Writer(out, compression=CompressionType.LZ4)
    writer.start(profile="ros2", library="sawdds.record")
    schemas = {}
    tracks = [Track(client, e, writer, schemas, args.out) for e in endpoints]
    deadline = time.monotonic() + args.wait
    while not all(t.reader.get_matched_publications() for t in tracks) and time.monotonic() < deadline:
        time.sleep(0.005)
    print("ready", flush=True)
    end = time.monotonic() + args.seconds if args.seconds else None
    while not stop[0] and (end is None or time.monotonic() < end):
        if not sum(t.take(writer) for t in tracks):
            time.sleep(0.002)
    time.sleep(0.05)  # what was on its way when told to stop
    # Then what is still queued, for at most a second: a stream the recorder cannot keep up with
    # (1 kHz rows on a loaded machine) never runs dry, and a recorder told to stop must stop.
    drained_by = time.monotonic() + 1.0
    while sum(t.take(writer) for t in tracks) and time.monotonic() < drained_by:
        pass
    writer.finish()
    out.close()
    for t in tracks:
        t.csv_file.close()
    stats = {t.endpoint.component_name: t for t in tracks if t.cls is msgs.TaskStatistics}
    every_row = ("read",)  # a latched state or an event is not published every cycle
    print(json.dumps({"files": [mcap_path] + [t.csv_path for t in tracks],
                      "topics": {t.topic: t.summary(stats.get(t.endpoint.component_name) if t.endpoint.kind in every_row
                                                    and not latched(t.endpoint) else None) for t in tracks}}),
          flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
