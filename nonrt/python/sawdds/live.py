"""A live, thread-safe picture of a sawrt system over DDS, kept by background threads.

`Live` reads the registry (every gateway's manifest and whether the gateway is alive), each
component's operating state and refusals, and the topics a caller watches (a state from its
display stream, which the gateway publishes at a display rate for live views), in a thread of its own:
a caller (a GUI's event loop) only ever copies what is there, under a lock, and never waits on the
network. Commands and qualified reads go through a second thread, whose results the caller
collects with `results()`. Every sample taken counts in the statistics; the window kept for
drawing is the last `window` seconds.
"""
import collections
import json
import os
import queue
import random
import signal
import subprocess
import sys
import threading
import time

import numpy as np
from cyclonedds._clayer import ddspy_take
from cyclonedds.core import InstanceState, SampleState, ViewState
from cyclonedds.internal import InvalidSample

from .client import Client, latched
from . import cdr, msgs, values

ANY = SampleState.Any | ViewState.Any | InstanceState.Any

FAULT = "FAULT"
# A state reader's history (keep last), and the most one take gets: a take that gets this many
# emptied a full history, whose oldest samples were overwritten before it.
READER_DEPTH = 1024
# What a component says it is (kind, variant, roles and the servers playing them, declared
# settings): every component's is read, as its operating state is.
DESCRIPTION = "saw_msgs::msg::dds_::ComponentDescription_"


class Series:
    """One topic: its last sample, a time window of its numbers (numpy, for drawing), statistics
    over every sample. Samples come in batches as bytes: the numbers of a batch of one layout are
    decoded in one numpy call (sawdds.cdr), the rest one by one; only each batch's newest sample
    becomes a Python message (for `latest`)."""

    def __init__(self, endpoint, window: float):
        self.endpoint = endpoint
        self.window = window
        self.cls = msgs.BY_DDS_NAME[endpoint.dds_type]
        self.names = None  # the numeric leaves, from the first sample
        self.layout = None  # sawdds.cdr.Layout of the first sample, None if it has none
        self.times = np.empty(0)
        self.rows = np.empty((0, 0))
        self.used = 0  # rows of times/rows in use (the oldest first)
        self.count = 0
        self.stats = None  # [n, min, max, sum, sum of squares] per leaf, numpy
        self.last = None
        self.last_time = None  # the sample's source time (s, wall clock)
        self.received_at = None  # when it was taken (s, monotonic)
        self.log = collections.deque(maxlen=500)  # (time, text) for events
        self.logged = 0  # entries ever added to the log (it keeps the last 500)
        self.logs = endpoint.kind.endswith("event") or self.cls in (msgs.StringStamped, msgs.OperatingState)
        self.tally = None  # sawdds.tally.Tally when a window is counted (Live.tally)

    def add(self, sample, t: float):
        """One decoded sample (events, latched states, and what the fast path cannot lay out)."""
        if self.tally is not None:
            self.tally.add([t])
        self._add(sample, t)

    def _add(self, sample, t: float):
        self.count += 1
        self.last, self.last_time, self.received_at = sample, t, time.monotonic()
        if self.logs:
            self.log.append((t, values.text(sample)))
            self.logged += 1
        nums = values.numbers(sample)
        if not nums:
            return
        if self.names is None:
            self.names = list(nums)
        self._append(np.array([t]), np.array([[nums.get(n, np.nan) for n in self.names]]))

    def add_raw(self, batch, history_full: bool = False):
        """A batch of (bytes, source time in s) of one topic, oldest first; `history_full`: the take
        that got it emptied a full reader history (older samples may have been overwritten)."""
        if self.tally is not None:
            self.tally.add([t for _, t in batch], history_full)
        datas = [d for d, _ in batch]
        if self.names is None:
            first = self.cls.deserialize(datas[0])
            self.names = list(values.numbers(first))
            try:
                self.layout = cdr.Layout(self.cls, datas[0], self.names) if self.names else None
            except (TypeError, ValueError):
                self.layout = None
        decoded = self.layout.decode(datas) if self.layout is not None else None
        if decoded is None:  # laid out otherwise (or not numeric): one by one
            for d, t in batch:
                self._add(self.cls.deserialize(d), t)
            return
        self.count += len(batch)
        self.last = self.cls.deserialize(datas[-1])
        self.last_time, self.received_at = batch[-1][1], time.monotonic()
        self._append(np.fromiter((t for _, t in batch), float, len(batch)), decoded[0])

    def _append(self, ts, vals):
        n, k = vals.shape
        if self.stats is None:
            self.stats = [0, np.full(k, np.inf), np.full(k, -np.inf), np.zeros(k), np.zeros(k)]
        st = self.stats
        st[0] += n
        st[1] = np.fmin(st[1], vals.min(axis=0))
        st[2] = np.fmax(st[2], vals.max(axis=0))
        st[3] += vals.sum(axis=0)
        st[4] += (vals * vals).sum(axis=0)
        # Drop what left the window, then grow (doubling) if the rest does not fit.
        newest = ts[-1]
        keep = self.used - int(np.searchsorted(self.times[:self.used], newest - self.window, side="left"))
        if keep < self.used:
            self.times[:keep] = self.times[self.used - keep:self.used]
            self.rows[:keep] = self.rows[self.used - keep:self.used]
            self.used = keep
        if self.used + n > len(self.times) or self.rows.shape[1] != k:
            cap = max(1024, 2 * (self.used + n))
            times, rows = np.empty(cap), np.empty((cap, k))
            times[:self.used] = self.times[:self.used]
            if self.rows.shape[1] == k:
                rows[:self.used] = self.rows[:self.used]
            else:
                self.used = 0
            self.times, self.rows = times, rows
        self.times[self.used:self.used + n] = ts
        self.rows[self.used:self.used + n] = vals
        self.used += n

    def window_arrays(self, max_points: int):
        """(times, rows) of the window, at most `max_points` (every k-th), with a NaN row inserted
        where the samples stopped for longer than usual (a plot draws a gap there, not a line)."""
        t, r = self.times[:self.used], self.rows[:self.used]
        if self.used < 2:
            return t.copy(), r.copy()
        step = max(1, self.used // max_points)
        t, r = t[::step], r[::step]
        dt = np.diff(t)
        usual = float(np.median(dt)) if len(dt) else 0.0
        breaks = np.nonzero(dt > max(4 * usual, 0.05))[0] if usual > 0 else np.nonzero(dt > 0.05)[0]
        if len(breaks):
            t = np.insert(t, breaks + 1, t[breaks] + dt[breaks] / 2)
            r = np.insert(r, breaks + 1, np.nan, axis=0)
        return t, r


def _lost_rejected(reader):
    """(samples lost, samples rejected) that Cyclone DDS counted on `reader` so far."""
    return reader.get_sample_lost_status().total_count, reader.get_sample_rejected_status().total_count


class Live:
    """The system as the registry and the watched topics show it, kept up to date off the caller's thread."""

    def __init__(self, domain: int = 0, window: float = 10.0, period: float = 0.02, full_rate: bool = False):
        self.client = Client(domain)
        self.domain = domain
        # A state's samples come from its display stream (the gateway's display rate), unless
        # `full_rate`: every row, as a recorder takes them (what the window cost before there was one).
        self.full_rate = full_rate
        self.window, self.period = window, period
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._wanted = set()  # topics to watch once the registry names them
        self._readers = {}  # topic -> (reader, Series)
        self._tally_window = None  # (start, end) that tally() set, for readers opened later
        self._errors = {}  # component -> (reader, deque of (time, text))
        self._gateways = {}  # name -> dict
        self._components = {}  # name -> dict
        self._recording = None  # the recorder process and what it said (record())
        self._jobs = queue.Queue()
        self._results = queue.Queue()
        self._writers = {}
        self._query_id = random.getrandbits(63)
        self._query_number = 0
        self.loop_seconds = 0.0  # time spent in the reading loop (for the headless benchmark)
        self._threads = [threading.Thread(target=self._read_loop, name="sawdds-live", daemon=True),
                         threading.Thread(target=self._job_loop, name="sawdds-commands", daemon=True)]
        for t in self._threads:
            t.start()

    def close(self):
        self._stop.set()
        self._jobs.put(None)
        for t in self._threads:
            t.join(timeout=2)
        self.stop_recording()

    # ---- what the caller reads (copies, under the lock) ----

    def gateways(self) -> dict:
        with self._lock:
            return {k: dict(v) for k, v in self._gateways.items()}

    def components(self) -> dict:
        with self._lock:
            return {k: dict(v) for k, v in self._components.items()}

    def endpoints(self, component: str) -> list:
        with self._lock:
            c = self._components.get(component)
            return list(c["endpoints"]) if c else []

    def description(self, component: str):
        """The saw_msgs/ComponentDescription `component` publishes (latched), or None before it
        arrives or when the component has none."""
        with self._lock:
            c = self._components.get(component)
            for e in c["endpoints"] if c else []:
                if e.kind == "read" and e.dds_type == DESCRIPTION and e.topic in self._readers:
                    return self._readers[e.topic][1].last
            return None

    def watch(self, topic: str):
        """Starts taking `topic`'s samples (now, or when a gateway serves it)."""
        with self._lock:
            self._wanted.add(topic)

    def tally(self, start: float, end: float):
        """From now on, counts each watched topic's samples written in [start, end) (wall clock, s)
        and those missing between them (sawdds.tally); tallies() gives the counts."""
        from .tally import Tally
        with self._lock:
            self._tally_window = (start, end)
            for reader, series in self._readers.values():
                series.tally = Tally(start, end, *_lost_rejected(reader))

    def tallies(self) -> dict:
        """{topic: Tally.summary()} of the window tally() set (empty before)."""
        with self._lock:
            return {t: s.tally.summary(*_lost_rejected(r)) for t, (r, s) in self._readers.items()
                    if s.tally is not None}

    def watched(self) -> list:
        with self._lock:
            return sorted(self._readers)

    def source(self, topic: str) -> str:
        """The DDS topic a watched `topic` is read from: its display stream, when the gateway
        publishes one and this Live is not `full_rate`; else `topic` itself ("" if not read yet)."""
        with self._lock:
            r = self._readers.get(topic)
            return r[0].topic.name if r else ""

    def latest(self, topic: str):
        """(sample, source time) of the newest sample of a watched topic, or (None, None)."""
        with self._lock:
            r = self._readers.get(topic)
            return (r[1].last, r[1].last_time) if r else (None, None)

    def series(self, topic: str, max_points: int = 2000):
        """(names, times, rows) of the last `window` seconds as numpy arrays, decimated to at most
        `max_points` for drawing, a NaN row where the samples stopped (a gap)."""
        with self._lock:
            r = self._readers.get(topic)
            if not r or not r[1].names:
                return [], np.empty(0), np.empty((0, 0))
            t, rows = r[1].window_arrays(max_points)
            return list(r[1].names), t, rows

    def statistics(self, topic: str) -> dict:
        """{leaf: (count, min, max, mean, rms)} over every sample taken since watching began."""
        with self._lock:
            r = self._readers.get(topic)
            if not r or r[1].stats is None:
                return {}
            n, lo, hi, total, squares = r[1].stats
            return {name: (n, float(lo[i]), float(hi[i]), float(total[i] / n), float((squares[i] / n) ** 0.5))
                    for i, name in enumerate(r[1].names)}

    def count(self, topic: str) -> int:
        with self._lock:
            r = self._readers.get(topic)
            return r[1].count if r else 0

    def log(self, topic: str, after: int = 0):
        """(entries ever logged, [(time, text) logged after the first `after`]) of a watched topic's
        events (the last 500 are kept)."""
        with self._lock:
            r = self._readers.get(topic)
            if not r:
                return 0, []
            s = r[1]
            new = min(s.logged - after, len(s.log))
            return s.logged, list(s.log)[len(s.log) - new:] if new > 0 else []

    def errors(self, component: str) -> list:
        """(time, text) of the gateway's refusals and fault reasons for `component`, oldest first
        (the last 200)."""
        with self._lock:
            e = self._errors.get(component)
            return list(e[1]) if e else []

    def error_count(self, component: str) -> int:
        """Errors ever taken for `component` (a mark for errors_after)."""
        with self._lock:
            e = self._errors.get(component)
            return e[2][0] if e else 0

    def errors_after(self, component: str, after: int = 0):
        """(errors ever taken for `component`, [(time, text) taken after the first `after`])."""
        with self._lock:
            e = self._errors.get(component)
            if not e:
                return 0, []
            new = min(e[2][0] - after, len(e[1]))
            return e[2][0], list(e[1])[len(e[1]) - new:] if new > 0 else []

    # ---- commands (run in the command thread; results() hands back what happened) ----

    def send(self, topic: str, sample, tag=None):
        """Sends a command once its gateway has matched our writer; results() then holds (tag, ok, text)."""
        self._jobs.put(("send", topic, sample, tag))

    def prepare(self, topic: str):
        """Makes the writer of a command topic now (when a gateway serves it), so that the first
        command sent on it does not wait for the writer to be made and matched."""
        self._jobs.put(("prepare", topic))

    def query(self, topic: str, data: bytes, tag=None, timeout: float = 2.0):
        """Asks a qualified read (rq/ topic) with the qualifier's bytes; results() then holds
        (tag, ok, the reply as text or why not)."""
        self._jobs.put(("query", topic, data, tag, timeout))

    def results(self) -> list:
        out = []
        while True:
            try:
                out.append(self._results.get_nowait())
            except queue.Empty:
                return out

    # ---- recording (a process of its own: sawdds.record) ----

    def record(self, topics, directory: str):
        """Starts recording every sample of `topics` to <directory>/recording.mcap (ROS 2 types) and
        one CSV per topic, in a recorder process of its own (sawdds.record: nothing it does waits on
        this process's interpreter, and nothing this process does makes it miss a sample)."""
        os.makedirs(directory, exist_ok=True)
        self.stop_recording()
        cmd = [sys.executable, "-m", "sawdds.record", "--domain", str(self.domain),
               "--out", directory] + [a for t in topics for a in ("--topic", t)]
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(
            [os.path.dirname(os.path.dirname(os.path.abspath(__file__)))] + sys.path))
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        rec = {"directory": directory, "process": proc, "ready": False, "summary": None, "error": ""}

        def follow():  # the recorder's lines: "ready", then one JSON summary when it stops
            for line in proc.stdout:
                if line.startswith("ready"):
                    rec["ready"] = True
                elif line.startswith("{"):
                    rec["summary"] = json.loads(line)
            rec["error"] = proc.stderr.read().strip()
        rec["thread"] = threading.Thread(target=follow, name="sawdds-recorder", daemon=True)
        rec["thread"].start()
        with self._lock:
            self._recording = rec

    def recording(self):
        """None, or {"directory", "ready" (the recorder's readers matched), "error"} of the recording."""
        with self._lock:
            rec = self._recording
        if rec is None:
            return None
        return {"directory": rec["directory"], "ready": rec["ready"],
                "error": rec["error"] if rec["process"].poll() not in (None, 0) else ""}

    def stop_recording(self, timeout: float = 10.0):
        """Stops the recorder; its summary ({"files": [...], "topics": {topic: {"samples", "missed",
        ...}}}) or None if nothing was recording (or the recorder failed: {"error": why})."""
        with self._lock:
            rec, self._recording = self._recording, None
        if rec is None:
            return None
        p = rec["process"]
        if p.poll() is None:
            p.send_signal(signal.SIGINT)
        hung = False
        try:
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            hung = True
            p.send_signal(signal.SIGUSR1)  # it prints where each of its threads is (faulthandler)
            time.sleep(1.0)
            p.kill()
            p.wait()
        rec["thread"].join(timeout=2)
        if hung:
            return {"error": f"the recorder did not stop within {timeout:g} s (killed); where it was: "
                             + (rec["error"] or "(nothing said)"), "files": [], "topics": {}}
        return rec["summary"] or {"error": rec["error"] or f"the recorder exited with {p.returncode}",
                                  "files": [], "topics": {}}

    # ---- the reading thread ----

    def _endpoint(self, topic):
        """The live endpoint of `topic`; a read before an event of the same topic (an operating state is
        both): a best-effort reader matches the state writer and the reliable event writer alike."""
        found = [e for c in self._components.values() if c["gone_at"] is None for e in c["endpoints"]
                 if e.topic == topic]
        found.sort(key=lambda e: e.kind != "read")
        return found[0] if found else None

    def _update_registry(self):
        self.client.take_manifests()
        manifests = dict(self.client._manifests)
        alive = self.client.alive()
        now = time.time()
        with self._lock:
            # Gone gateways first: a component a restarted gateway serves again is its, not the old one's.
            for g, m in sorted(manifests.items(), key=lambda gm: alive.get(gm[0], False)):
                was = self._gateways.get(g)
                live = alive.get(g, False)
                comps = sorted({e.component_name for e in m.endpoints})
                gone_at = None if live else (was["gone_at"] if was and was["gone_at"] else now)
                self._gateways[g] = {"host": m.host, "pid": m.pid, "state": m.state, "alive": live,
                                     "components": comps, "gone_at": gone_at}
                for c in comps:
                    eps = [e for e in m.endpoints if e.component_name == c]
                    old = self._components.get(c, {})
                    self._components[c] = {
                        "gateway": g, "host": m.host, "endpoints": eps,
                        "interfaces": sorted({e.interface_name for e in eps}),
                        "state": old.get("state", ""), "state_time": old.get("state_time"),
                        "fault_reason": old.get("fault_reason", ""), "fault_time": old.get("fault_time"),
                        "gone_at": None if live else (old.get("gone_at") or now),
                    }
                # A component a live gateway no longer lists has gone (detached).
                for name, c in self._components.items():
                    if c["gateway"] == g and name not in comps and c["gone_at"] is None:
                        c["gone_at"] = now
            for name, c in self._components.items():
                if c["gone_at"] is None:
                    for e in c["endpoints"]:
                        if e.topic and e.kind == "read" and (e.name == "operating_state" or e.dds_type == DESCRIPTION):
                            self._wanted.add(e.topic)
                if name not in self._errors:
                    self._errors[name] = (self.client.error_reader(name),
                                          collections.deque(maxlen=200), [0])

    def _open_readers(self):
        with self._lock:
            pending = [t for t in self._wanted if t not in self._readers]
            found = [(t, self._endpoint(t)) for t in pending]
        for t, e in found:
            if e is None or not e.topic or e.dds_type not in msgs.BY_DDS_NAME:
                continue
            # Deep enough that nothing is lost between two passes of the loop at 1 kHz.
            reader = self.client.reader_for(e, depth=1 if latched(e) else READER_DEPTH, display=not self.full_rate)
            series = Series(e, self.window)
            with self._lock:
                if self._tally_window is not None:
                    from .tally import Tally
                    series.tally = Tally(*self._tally_window)
                self._readers[t] = (reader, series)

    def _take(self):
        with self._lock:
            items = list(self._readers.items())
            errs = list(self._errors.items())
        for topic, (reader, series) in items:
            if series.logs:  # events and latched states: few, decoded as messages
                samples = [s for s in reader.take(N=1024) if not isinstance(s, InvalidSample)]
                if not samples:
                    continue
                with self._lock:
                    for s in samples:
                        series.add(s, s.sample_info.source_timestamp * 1e-9)
                        if isinstance(s, msgs.OperatingState):
                            self._state_changed(series.endpoint.component_name, s)
                continue
            got = ddspy_take(reader._ref, ANY, READER_DEPTH)
            if isinstance(got, int) or not got:
                continue
            batch = [(d, i.source_timestamp * 1e-9) for d, i in got if i.valid_data]
            if batch:
                with self._lock:
                    series.add_raw(batch, history_full=len(got) >= READER_DEPTH)
        for comp, (reader, log, taken) in errs:
            got = [s for s in reader.take(N=64) if isinstance(s, msgs.StringStamped)]
            if got:
                with self._lock:
                    for s in got:
                        log.append((s.sample_info.source_timestamp * 1e-9, s.string))
                        taken[0] += 1
                        c = self._components.get(comp)
                        ts = s.sample_info.source_timestamp * 1e-9
                        # The gateway says FAULT on both topics; whichever comes first counts. A
                        # late joiner also gets the topic's last 16 lines: a FAULT older than the
                        # state it has (cleared since) does not count.
                        if c is not None and s.string.startswith(FAULT) and ts >= (c.get("state_time") or 0):
                            if c["state"] != FAULT:
                                c["state"] = FAULT
                                c["state_time"] = c["fault_time"] = s.sample_info.source_timestamp * 1e-9
                            c["fault_reason"] = s.string

    def _state_changed(self, component, s):
        c = self._components.get(component)
        if c is None or c["state"] == s.state:
            return
        c["state"], c["state_time"] = s.state, s.sample_info.source_timestamp * 1e-9
        if s.state == FAULT:
            c["fault_time"] = c["state_time"]
            if not c["fault_reason"]:
                errs = self._errors.get(component)
                c["fault_reason"] = errs[1][-1][1] if errs and errs[1] else "(no reason received)"
        else:
            c["fault_reason"] = ""

    def _read_loop(self):
        last_registry = 0.0
        while not self._stop.is_set():
            t0 = time.perf_counter()
            # Samples first: what a gateway said before it left (its FAULT) is taken before its leaving.
            self._take()
            if t0 - last_registry > 0.05:
                self._update_registry()
                self._open_readers()
                last_registry = t0
            self.loop_seconds += time.perf_counter() - t0
            self._stop.wait(self.period)

    # ---- the command thread ----

    def _job_loop(self):
        while True:
            job = self._jobs.get()
            if job is None or self._stop.is_set():
                return
            try:
                if job[0] == "prepare":
                    self._writer(job[1])
                elif job[0] == "send":
                    self._results.put((job[3], *self._send(job[1], job[2])))
                else:
                    self._results.put((job[3], *self._query(*job[1:3], job[4])))
            except Exception as e:  # a bad endpoint or type: said, not raised in a thread nobody watches
                if job[0] != "prepare":
                    self._results.put((job[3], False, f"{type(e).__name__}: {e}"))

    def _writer(self, topic):
        """The writer of command `topic` (made once), or None while no live gateway serves it."""
        with self._lock:
            e = self._endpoint(topic)
        if e is None:
            return None
        if topic not in self._writers:
            self._writers[topic] = self.client.writer_for(e)[0]
        return self._writers[topic]

    def _send(self, topic, sample, wait: float = 3.0):
        w = self._writer(topic)
        if w is None:
            return False, f"no live gateway serves {topic}"
        deadline = time.monotonic() + wait
        while not w.get_matched_subscriptions():
            if time.monotonic() > deadline:
                return False, f"the gateway did not match a writer of {topic} within {wait:g} s"
            time.sleep(0.01)
        w.write(sample)
        return True, "delivered"

    def _query(self, topic, data, timeout):
        with self._lock:
            e = self._endpoint(topic)
        if e is None:
            return False, f"no live gateway serves {topic}"
        reply_topic = topic.replace("rq/", "rr/", 1)[: -len("Request")] + "Reply"
        if topic not in self._writers:
            from cyclonedds.core import Policy, Qos
            from cyclonedds.pub import DataWriter
            from cyclonedds.sub import DataReader
            from .client import XCDR1
            qos = Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(16), XCDR1)
            self._writers[topic] = (
                DataWriter(self.client.participant, self.client._topic(topic, msgs.Query), qos=qos),
                DataReader(self.client.participant, self.client._topic(reply_topic, msgs.QueryReply), qos=qos))
        w, r = self._writers[topic]
        self._query_number += 1
        q = msgs.Query(client=self._query_id, number=self._query_number, data=list(data))
        deadline = time.monotonic() + timeout
        while not (w.get_matched_subscriptions() and r.get_matched_publications()):
            if time.monotonic() > deadline:
                return False, f"no gateway answers {topic}"
            time.sleep(0.01)
        next_ask = 0.0
        while time.monotonic() < deadline:
            # Asked again until answered: the reply writer may not know our reader yet (a query is const).
            if time.monotonic() >= next_ask:
                w.write(q)
                next_ask = time.monotonic() + 0.2
            for rep in r.take(N=64):
                if isinstance(rep, msgs.QueryReply) and rep.client == q.client and rep.number == q.number:
                    if rep.status != 0:
                        return False, f"refused (status {rep.status})"
                    return True, values.unpack(e.result_type, bytes(rep.data))
            time.sleep(0.005)
        return False, f"no reply within {timeout:g} s"
