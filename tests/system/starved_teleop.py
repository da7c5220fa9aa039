"""A starved teleoperation faults, says why, and leaves every device safe.

saw-rt runs the shipped simulated teleoperation (config/teleop-sim.yaml, deadline policies as
shipped: none set, so the deployment's standard one) with its tasks pinned to CPU 0, and the test
starves them there:
- `stall`: the whole process stopped (SIGSTOP) for 120 ms, as a machine that freezes does:
  the first wake-up after it finds more than 50 periods missed in a row;
- `starve`: a SCHED_FIFO process above the tasks' priority on the same CPU, busy 2 ms of every
  3 (the emulated PREEMPT_RT guest ran these loops at a third of their rate): never 50 periods in
  a row, but more than a tenth of each second's periods.

Asserted for each: both devices end in FAULT naming their missed deadlines with the figures, the
teleoperation in FAULT naming its own missed deadline or a device's FAULT (whichever task's
window closed first), both devices' last output the safe one (zero force), and the tracking error
over the ENABLED cycles (up to the fault) within a bound (the same run unstarved, plus 5 mm): a
late loop faults before it drives anything astray. Then the policy switched off (`deadline: off`
on every task) turns the same starvation into no deadline FAULT and no device FAULT: the check is
what faults (starved past its stale_timeout, the teleoperation's staleness check may still fault
it, later and saying so).

Usage: starved_teleop.py <saw-rt> <source dir>
"""

import os
import re
import signal
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from service_ready import NotifySocket  # noqa: E402

SAW_RT, SRC = sys.argv[1:3]
CPU = 0


def fail(message, *outputs):
    print(f"FAIL: {message}", file=sys.stderr)
    for o in outputs:
        print(o, file=sys.stderr)
    sys.exit(1)


def can_fifo():
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(1))
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        return True
    except PermissionError:
        return False


def hog(seconds):
    """A child at SCHED_FIFO 95 on CPU: busy 2 ms of every 3 for `seconds`."""
    code = f"""
import os, time
os.sched_setaffinity(0, {{{CPU}}})
os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(95))
end = time.monotonic() + {seconds}
while time.monotonic() < end:
    t = time.monotonic() + 0.002
    while time.monotonic() < t:
        pass
    time.sleep(0.001)
"""
    return subprocess.Popen([sys.executable, "-c", code])


def deployment(tmp, deadline_off):
    with open(os.path.join(SRC, "config", "teleop-sim.yaml")) as f:
        text = f.read()
    pinned = re.sub(r"task: \{period: 1ms, priority: (\d+)", rf"task: {{period: 1ms, priority: \1, cpu: {CPU}", text)
    if pinned.count(f"cpu: {CPU}") != 3:
        fail("config/teleop-sim.yaml changed: its three tasks were not pinned", pinned)
    if deadline_off:
        pinned = pinned.replace(f"cpu: {CPU}", f"cpu: {CPU}, deadline: off")
    path = os.path.join(tmp, "starved.yaml")
    with open(path, "w") as f:
        f.write(pinned)
    return path


def run(tmp, how, deadline_off=False):
    """saw-rt for 6 s; starved by `how` from 2 s after READY=1. Returns (stdout, stderr, None)."""
    notify = NotifySocket()
    p = subprocess.Popen([SAW_RT, deployment(tmp, deadline_off), "--duration", "6"],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=notify.env())
    if not notify.wait("READY=1", p, 60):
        p.kill()
        fail(f"{how}: saw-rt never said READY=1", *p.communicate())
    notify.close()
    time.sleep(2)  # the unstarved part of the run: the reference for the tracking bound
    h = None
    if how == "none":
        pass
    elif how == "stall":
        p.send_signal(signal.SIGSTOP)
        time.sleep(0.12)
        p.send_signal(signal.SIGCONT)
    else:
        h = hog(2.5)
    out, err = p.communicate(timeout=60)
    if h:
        h.wait()
    print(f"--- {how}{' (deadline off)' if deadline_off else ''}:\n{out}{err[-2000:]}")
    if p.returncode != 0:
        fail(f"{how}: saw-rt exited {p.returncode}", out, err)
    return out, err, None


def tracking_max(how, out, at_least=1000):
    """The teleoperation's largest tracking error over its ENABLED cycles (up to a fault), m.

    A run that faults judges the bound on the cycles before its fault: at least half a second of
    them (a loaded machine may starve the first window itself, before the hog does: that run's
    FAULT is as named and as safe, and it came earlier)."""
    m = re.search(r"^\s*teleop: .*tracking error \|e_s\| RMS [0-9.]+ mm, max ([0-9.]+) mm over (\d+) enabled", out, re.M)
    if not m or int(m.group(2)) < at_least:
        fail(f"{how}: no tracking error over at least {at_least} enabled cycles in the summary", out)
    return float(m.group(1)) * 1e-3


def check(how, out, err, bound, kind):
    for name in ("teleop", "master", "slave"):
        if not re.search(rf"^\s*{name}: .*FAULT", out, re.M):
            fail(f"{how}: {name} did not end in FAULT", out)
    for name in ("master", "slave"):
        if not re.search(rf"^\s*{name}: .*the last: deadline missed: \d+ periods", out, re.M):
            fail(f"{how}: {name}'s FAULT does not name the missed deadline", out)
    # The three tasks judge their own periods; whichever finds the breach first faults. The
    # teleoperation's FAULT names its own missed deadline, or a device's FAULT (which, above,
    # names that device's missed deadline) when a device's window closed first.
    m = re.search(r"^\s*teleop: FAULT \((deadline missed: \d+ periods|(master|slave) device in FAULT).*", out, re.M)
    if not m or (m.group(0).find("deadline missed") >= 0 and not re.search(kind, m.group(0))):
        fail(f"{how}: the teleoperation's FAULT names neither its missed deadline ({kind}) nor a device's FAULT", out)
    if not any(re.search(rf"deadline missed: \d+ periods {kind}", line) for line in out.splitlines()):
        fail(f"{how}: no FAULT names a deadline missed {kind}", out)
    if not re.search(r"deadline: \d+ (of \d+ )?periods missed", err):
        fail(f"{how}: no log line says how many periods were missed", err)
    for name in ("master", "slave"):
        if not re.search(rf"^\s*{name}: FAULT, its last output the safe one \(zero force\)", out, re.M):
            fail(f"{how}: {name}'s last output was not the safe one", out)
    worst = tracking_max(how, out, at_least=500)
    at = re.search(r"at t=([0-9.]+) s", m.group(0))
    early = " (before the starvation: the machine starved the first window itself)" if at and float(at.group(1)) < 1.9 else ""
    print(f"ok: {how}: {m.group(0).strip()[:160]}; tracking error max {worst * 1e3:.2f} mm up to the fault "
          f"(bound {bound * 1e3:.2f} mm){early}")
    if worst > bound:
        fail(f"{how}: the tracking error reached {worst * 1e3:.1f} mm before the fault (bound {bound * 1e3:.1f} mm)")


if not can_fifo():
    print("SKIP: starving the loop needs SCHED_FIFO (run as root, or with an rtprio limit)")
    sys.exit(77)
with tempfile.TemporaryDirectory(prefix="sawstarved") as tmp:
    # The bound: the same run unstarved (on this machine, now), plus 5 mm.
    out, _, _ = run(tmp, "none")
    bound = tracking_max("unstarved", out) + 0.005
    out, err, _ = run(tmp, "stall")
    check("stall", out, err, bound, r"in a row")
    out, err, _ = run(tmp, "starve")
    check("starve", out, err, bound, r"in a window")
    out, err, _ = run(tmp, "starve", deadline_off=True)
    if "deadline missed" in out or re.search(r"^\s*(master|slave): .*FAULT", out, re.M):
        fail("with `deadline: off` the starved run still faulted on a deadline, or a device faulted: "
             "the deadline FAULT came from elsewhere", out)
    # Starved harder than its stale_timeout (an ASan build on a loaded machine), the teleoperation's
    # input staleness check may still catch it, later and as what it is: that is the other net, and
    # no deadline verdict. Anything else faulting is a failure.
    m = re.search(r"^\s*teleop: FAULT \((.*)", out, re.M)
    if m and not re.match(r"(master|slave) input stale: ", m.group(1)):
        fail(f"with `deadline: off` the teleoperation faulted on something else: {m.group(0).strip()}", out)
    caught = f"; its input staleness check caught it ({m.group(1)[:60]})" if m else ""
    print(f"ok: with `deadline: off` no deadline FAULT, no device FAULT (tracking error max "
          f"{tracking_max('off', out) * 1e3:.2f} mm){caught}: the deadline check is what faults")
