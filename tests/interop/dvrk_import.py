"""The da Vinci stream, imported: a Cyclone DDS publisher (Python) replays a synthetic dVRK master
(rt/MTML/measured_cp, measured_cv, operating_state, as the dVRK's ROS 2 stack publishes them); a
real saw-rt process whose deployment imports it (`gateway: import:` by arm name) runs a simulated
slave and the teleoperation task connected to it exactly as to a local master. The slave follows
(the stream runs until teleoperation was ENABLED for 2000 cycles, as the record shows); when the
stream stops, teleoperation goes to FAULT and stays there.

usage: dvrk_import.py SAW_RT SAW_GATEWAY
"""
import csv
import itertools
import math
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time


import harness  # noqa: E402
from harness import check, dds_domain, exit_code  # noqa: E402
from sawdds import Client, msgs  # noqa: E402
from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402


class SyntheticMaster(threading.Thread):
    """An MTM's CRTK stream at ~1 kHz: x follows a 0.5 Hz sinusoid of 3 cm around a home pose."""

    def __init__(self, client, arm):
        super().__init__(daemon=True)
        qos = Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(1),
                  Policy.DataRepresentation(use_cdrv0_representation=True))
        p = client.participant
        self.cp = DataWriter(p, client._topic(f"rt/{arm}/measured_cp", msgs.PoseStamped), qos=qos)
        self.cv = DataWriter(p, client._topic(f"rt/{arm}/measured_cv", msgs.TwistStamped), qos=qos)
        # The dVRK latches its operating state (transient local), as the import requires.
        latched = Qos(Policy.Reliability.Reliable(10**9), Policy.History.KeepLast(1),
                      Policy.Durability.TransientLocal, Policy.DataRepresentation(use_cdrv0_representation=True))
        self.state = DataWriter(p, client._topic(f"rt/{arm}/operating_state", msgs.OperatingState), qos=latched)
        self.running = True
        self.sent = 0

    def run(self):
        t0 = time.monotonic()
        self.state.write(msgs.OperatingState(state="ENABLED", is_homed=True))
        while self.running:
            t = time.monotonic() - t0
            now = time.time_ns()
            h = msgs.Header(stamp=msgs.Time(sec=now // 10**9, nanosec=now % 10**9), frame_id="MTML")
            x = 0.03 * math.sin(2 * math.pi * 0.5 * t)
            v = 0.03 * 2 * math.pi * 0.5 * math.cos(2 * math.pi * 0.5 * t)
            self.cp.write(msgs.PoseStamped(header=h, pose=msgs.Pose(position=msgs.Point(x=0.15 + x, y=0.0, z=-0.12))))
            self.cv.write(msgs.TwistStamped(header=h, twist=msgs.Twist(linear=msgs.Vector3(x=v))))
            self.sent += 1
            time.sleep(0.001)


ENGAGED = 2000  # ENABLED cycles of teleoperation before the stream is stopped


def rows_of(path):
    """The record's complete rows so far (it is written as the run goes, a few rows behind)."""
    try:
        with open(path) as f:
            lines = f.read().split("\n")[:-1]  # the last, maybe partial, line left out
    except FileNotFoundError:
        return []
    return list(csv.DictReader(lines))


def deployment(tag, domain, component, arm):
    return f"""deployment:
  name: dvrk-import-{tag}
components:
  - name: slave{tag}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params:
      model: omni
  - name: teleop{tag}
    type: teleop
    task: {{period: 1ms, priority: 79}}
    params:
      gains: {{master: 300, slave: 300}}
      force_limits: {{master: 3.0, slave: 3.0}}
      stale_timeout: 50ms
      startup_timeout: 10s  # the imported stream may take a moment to flow (DDS discovery)
connections:
  - {{client: teleop{tag}, required: master, server: {component}, provided: arm}}
  - {{client: teleop{tag}, required: slave, server: slave{tag}, provided: arm}}
record:
  columns: [slave{tag}.measured_cp, teleop{tag}.operating_state]
gateway:
  domain: {domain}
  import:
    - {{component: {component}, arm: {arm}}}
"""


def run(saw_rt, client, domain, tag, work):
    """One run: the stream until teleoperation was ENABLED for ENGAGED cycles, then silence.
    Returns why the run stalled (a FAULT before the stream stopped: the machine starved a process
    for over the stale timeout), or None; a stalled run must still end in FAULT and stay there."""
    arm, component, state = "MTML", f"mtml{tag}", f"teleop{tag}.operating_state"
    path, record = os.path.join(work, f"deploy{tag}.yaml"), os.path.join(work, f"run{tag}.csv")
    with open(path, "w") as f:
        f.write(deployment(tag, domain, component, arm))
    master = SyntheticMaster(client, arm)
    master.start()
    rt = out = None
    try:
        rt = subprocess.Popen([saw_rt, path, "--duration", "8", "--record", record], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
        # Until the record shows ENGAGED ENABLED cycles (or a FAULT): bounded, 6 s of the 8.
        give_up, seen = time.monotonic() + 6.0, []
        while time.monotonic() < give_up:
            seen = [r.get(state) for r in rows_of(record)]
            if seen.count("ENABLED") >= ENGAGED or "FAULT" in seen:
                break
            time.sleep(0.05)
        master.running = False
        stopped_at = len(seen)  # rows recorded when the stream stopped (at most a few behind)
        out, _ = rt.communicate(timeout=30)
        print(out)
        rows = rows_of(record) if os.path.exists(record) else []
        first_fault = next((i for i, r in enumerate(rows) if r[state] == "FAULT"), None)
        if first_fault is not None and first_fault < stopped_at:
            after = {r[state] for r in rows[first_fault:]}
            check(after == {"FAULT"}, f"after the stall teleoperation stayed in FAULT: {sorted(after)}")
            return next((l for l in out.splitlines() if "FAULT" in l), "a FAULT before the stream stopped")
        check(rt.returncode == 0, f"saw-rt started its gateway, which imported the master, and connected to it "
                                  f"(exit {rt.returncode})")
        check(len(rows) > 1000, f"recorded {len(rows)} rows")
        t0 = float(rows[0]["time"]) if rows else 0
        enabled = [r for r in rows[:first_fault] if r[state] == "ENABLED"]
        xs_before = [float(r[f"slave{tag}.measured_cp.x"]) for r in enabled]
        swing = (max(xs_before) - min(xs_before)) if xs_before else 0.0
        check(len(enabled) >= ENGAGED, f"teleoperation ENABLED while the stream ran ({len(enabled)} cycles)")
        check(swing > 0.03, f"the slave follows the imported master: it swung {swing * 100:.1f} cm (master: 6 cm)")
        check(first_fault is not None, "the stream stopping moved teleoperation to FAULT")
        if first_fault is not None:
            states_after = {r[state] for r in rows[first_fault:]}
            check(states_after == {"FAULT"}, f"and it stays there: {sorted(states_after)}")
            print(f"figure: FAULT {float(rows[first_fault]['time']) - t0:.3f} s into the run, "
                  f"{first_fault - stopped_at} rows after the stream's stop was seen (stale_timeout 50 ms)")
        return None
    finally:
        master.running = False
        if rt is not None and rt.poll() is None:
            rt.kill()
        imported = [l for l in (out or "").splitlines() if "imported" in l and l.startswith("saw-gateway:")]
        print(imported[-1] if imported else "(no gateway statistics)")
        check(bool(imported) and " 0 rejected" in imported[-1].split("imported")[1],
              "every imported sample was a valid value")


def main(saw_rt, saw_gateway):
    """A run in which the machine stalled (a FAULT before the stream stopped) gives no verdict if
    teleoperation stayed in FAULT, as it must; it is run again, up to three times, and a stall in
    all three fails."""
    domain = dds_domain()
    client = Client(domain)
    work = tempfile.mkdtemp()
    attempt = itertools.count(1)  # each run its own names
    harness.until_no_stall(lambda: run(saw_rt, client, domain, f"{os.getpid()}{next(attempt)}", work),
                           "the imported stream")
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
