"""config/canopen-sim.yaml end to end: saw-rt teleoperates three simulated CiA 402 drives.

Real processes on a virtual CAN bus of this test's own: saw-can-sim plays nodes 1-3, saw-rt runs
the shipped deployment (the bus renamed), which resets, configures and starts the nodes, enables
them and teleoperates the arm in CST with the simulated haptic master.

Checks, on each run's printed summary:
- normal run: saw-rt exits 0, the arm and the teleoperation end ENABLED, the tracking error is
  printed and below half the hand's 30 mm amplitude (an arm that did not follow would show about
  21 mm RMS), and the drives moved (saw-can-sim's positions);
- the drives are left disabled and pre-operational whenever saw-rt ends: after the normal run,
  and after a SIGTERM mid-run (frames on the bus before the process is gone);
- fault run: an over-current injected on node 2 faults the arm naming the emergency, and the
  teleoperation faults too, naming the slave (zero force on both sides).
Each run is judged on one of two outcomes (run_outcome.py): control as above, or — where this
machine cannot run the 1 kHz loops — a FAULT naming the missed deadline, the tracking up to it
bounded and every drive left safe. Never a run that drifted without faulting.

Usage: canopen_sim_teleop.py <saw-rt> <saw-can-sim> <canopen-sim.yaml>
(SAW_TEST_CANOPEN_BUS=socketcan:vcan0 runs both on that bus instead of a private virtual one)
"""

import os
import re
import signal
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "system"))
from service_ready import NotifySocket  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from run_outcome import TRACKING_MAX_MM, deadline_fault, outcome, tracking  # noqa: E402

SAW_RT, SIM, CONFIG = sys.argv[1:4]
SIM_ARGS = ["--node", "1", "--node", "2", "--node", "3", "--load-inertia", "0.002", "--friction", "2e-6"]


def fail(message, *outputs):
    print(f"FAIL: {message}", file=sys.stderr)
    for o in outputs:
        print(o, file=sys.stderr)
    sys.exit(1)


def run(tag, rt_seconds, inject=(), terminate_after=None):
    # SAW_TEST_CANOPEN_BUS: another bus, e.g. socketcan:vcan0 in the PREEMPT_RT guest (tests/kernel).
    bus = os.environ.get("SAW_TEST_CANOPEN_BUS") or f"virtual:sawcanteleop{os.getpid()}{tag}"
    with open(CONFIG) as f:
        text = f.read().replace("virtual:canopen-sim", bus)
    # The shipped file's staleness limits (10 ms for a drive's TPDOs, 20 ms for the teleoperation's
    # inputs, 150 ms for heartbeats) fault on a stall of the shared CI machine, as they should on a
    # lab PC; this test is about the path, so it allows 500 ms (stalls of 100 ms have been seen).
    text = re.sub(r"(\n(\s+)command_timeout: 20ms[^\n]*)", r"\1\n\2feedback_timeout: 500ms", text, count=1)
    text = text.replace("stale_timeout: 20ms", "stale_timeout: 500ms")
    text = text.replace("rpdo_deadline: 5ms", "rpdo_deadline: 500ms")
    text = text.replace("timeout: 150ms}", "timeout: 500ms}")
    # Time judged over 200 ms, not the default 1 s: a late loop faults before the arm drifts.
    text = text.replace("  name: canopen-sim\n", "  name: canopen-sim\n  deadline: {window: 200ms}\n")
    if any(x not in text for x in ("feedback_timeout: 500ms", "stale_timeout: 500ms", "timeout: 500ms}", "rpdo_deadline: 500ms",
                                 "deadline: {window: 200ms}")):
        fail("the deployment file changed: this test's edits no longer apply", text)
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(text)
        config = f.name
    sim = subprocess.Popen([SIM, "--bus", bus, *SIM_ARGS, *sum((["--inject", i] for i in inject), [])],
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        # The bus exists once saw-can-sim says where its drives are.
        ready = sim.stdout.readline()
        if "drives on" not in ready:
            fail("saw-can-sim did not start", ready, sim.stdout.read())
        if terminate_after is None:
            rt = subprocess.run([SAW_RT, config, "--duration", str(rt_seconds)], capture_output=True, text=True,
                                timeout=120)
        else:
            # Stopped as a service manager stops it: SIGTERM, no duration, `terminate_after` s
            # after saw-rt said it was ready (under emulation loading alone can take seconds).
            notify = NotifySocket()
            p = subprocess.Popen([SAW_RT, config], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                 env=notify.env())
            try:
                said_ready = notify.wait("READY=1", p, 120)
                notify.close()
                if not said_ready:
                    p.kill()
                    out, err = p.communicate()
                    fail("saw-rt never said READY=1 to its service manager", out, err)
                out, err = p.communicate(timeout=terminate_after)
                fail("saw-rt exited before it was terminated", out, err)
            except subprocess.TimeoutExpired:
                p.send_signal(signal.SIGTERM)
                out, err = p.communicate(timeout=60)
            rt = subprocess.CompletedProcess(p.args, p.returncode, out, err)
    finally:
        sim.terminate()
        sim_out = ready + sim.communicate(timeout=30)[0]
        os.unlink(config)
        shm = "/dev/shm/saw-can." + bus.split(":", 1)[1]
        if bus.startswith("virtual:") and os.path.exists(shm):
            os.unlink(shm)
    print(rt.stdout[-3000:])
    print(sim_out[-1500:])
    return rt, sim_out


def judged(rt, tag):
    """The run's outcome (run_outcome.py): control or a deadline FAULT, else the test fails."""
    if rt.returncode != 0:
        fail(f"{tag}: saw-rt exited {rt.returncode}", rt.stdout, rt.stderr)
    result = outcome(rt.stdout)
    if result is None:
        fail(f"{tag}: neither control (the arm and the teleoperation ENABLED) nor a FAULT naming a missed "
             f"deadline with the tracking up to it within {TRACKING_MAX_MM} mm", rt.stdout, rt.stderr)
    if result == "deadline":
        print(f"{tag}: the loops missed their deadlines on this machine and faulted: {deadline_fault(rt.stdout)}")
    return result


# A normal run.
rt, sim_out = run("ok", 4)
normal = judged(rt, "normal")
if normal == "control":
    rms = tracking(rt.stdout)[0]
    # SAW_TEST_CANOPEN_MAX_RMS_MM: a looser bound where the cycles run under software emulation (the
    # PREEMPT_RT guest without KVM), whose stalls short of a deadline fault the arm follows less well.
    max_rms = float(os.environ.get("SAW_TEST_CANOPEN_MAX_RMS_MM", "15"))
    if not rms < max_rms:
        fail(f"tracking error RMS {rms} mm: the arm did not follow the master", rt.stdout)


# saw-rt left every drive safe as it exited: disabled at a last SYNC, then pre-operational (a
# master that stops sends nothing again, so nothing may stay enabled on its last torque).
def drives_left_safe(sim_out, also_safe=()):
    left = re.findall(r"^\s*([123])\s+(\S+)\s+(.+?)\s{2,}\d+\s+(-?\d+)", sim_out, re.M)
    if sorted(n for n, *_ in left) != ["1", "2", "3"]:
        fail("saw-can-sim's table of drives is missing", sim_out)
    for node, nmt, state, _ in left:
        if nmt != "pre-operational" or (state != "switch on disabled" and state not in also_safe):
            fail(f"node {node} was left {nmt}, {state} when saw-rt exited (not pre-operational, "
                 "switch on disabled)", sim_out)
    return left


left = drives_left_safe(sim_out)
moved = [int(p) for n, _, _, p in left if n in "23"]
if normal == "control" and not any(abs(p) > 1000 for p in moved):
    fail("saw-can-sim's shoulder and elbow drives did not move", sim_out)
print(f"ok ({normal}): tracking error RMS/max/cycles {tracking(rt.stdout)}; every drive left disabled and "
      f"pre-operational; drive positions {moved}")

# SIGTERM mid-run: the same safe state, and an orderly summary (exit 0).
rt, sim_out = run("term", None, terminate_after=3)
if judged(rt, "SIGTERM") == "deadline":
    drives_left_safe(sim_out)
    print("ok: SIGTERM after a deadline FAULT left every drive disabled and pre-operational")
    # The over-current below is not told apart from a deadline FAULT that comes first.
    sys.exit(0)
m = re.search(r"teleop: ENABLED.* over (\d+) enabled cycles", rt.stdout)
if not m or int(m.group(1)) < 100:
    fail("the teleoperation was not running when SIGTERM came (fewer than 100 enabled cycles in 3 s after READY=1)",
         rt.stdout)
drives_left_safe(sim_out)
print(f"ok: SIGTERM after {m.group(1)} enabled cycles left every drive disabled and pre-operational")

# An over-current on the shoulder drive 2 s in.
rt, sim_out = run("fault", 4, inject=["2:over-current:2"])
named = (re.search(r"^\s*slave: FAULT", rt.stdout, re.M) and
         re.search(r"^\s*slave: .*shoulder_pitch.*continuous over-current", rt.stdout, re.M) and
         re.search(r"^\s*teleop: FAULT.*slave device in FAULT", rt.stdout, re.M))
if not named and deadline_fault(rt.stdout) and judged(rt, "over-current") == "deadline":
    # The loops faulted on their deadlines before the over-current could be told apart: the drives
    # are safe all the same (node 2 may be in its own fault: its power stage is off there too).
    drives_left_safe(sim_out, also_safe=("fault",))
    print("ok: a deadline FAULT came before the over-current; every drive left disabled and pre-operational")
    sys.exit(0)
if not (re.search(r"^\s*slave: FAULT", rt.stdout, re.M) and
        re.search(r"^\s*slave: .*shoulder_pitch.*continuous over-current", rt.stdout, re.M)):
    fail("the arm did not fault naming the over-current", rt.stdout, rt.stderr)
if not re.search(r"^\s*teleop: FAULT.*slave device in FAULT", rt.stdout, re.M):
    fail("the teleoperation did not fault naming the slave", rt.stdout)
print("ok: an over-current on node 2 faulted the arm and the teleoperation, each saying why")
