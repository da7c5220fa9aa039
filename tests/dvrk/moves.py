"""saw-rt moves the independent simulated dVRK arms (sim_arm.py, Cyclone DDS) the way an alignment
does before teleoperation: a DDS client (sawdds) sends the RT `dvrk_arm` device move_cp and
move_jp through saw-rt's gateway; the device checks them and passes them to the arm's read-write
import, which writes the dVRK's own topics; the arm plans the trajectory and gets there.

(a) a PSM: move_cp and move_jp reach the arm and it arrives at each goal; goals outside the
    device's workspace or joint limits never reach it; measured_js is the device's, named;
(b) kill -9 of saw-rt while the arm is still moving: the gateway's exit path sends `hold`, and
    the arm stops short of the goal;
(c) an MTM: `free` reaches it (then nothing of ours is left on it), and its body/measured_cf is
    the device's measured_cf.

Moves are not timed streams: the run judges no deadline and its staleness limit is 1 s, so that it
also runs under ASan (the import's read-write code, its exit path included). The simulated arm
behaves as the dVRK does while busy (its servo commands and hold pre-empt a
move: refuse_when_busy off). Each check is printed; the exit code is 1 if any failed.

usage: moves.py SAW_RT
"""
import math
import os
from contextlib import contextmanager
import signal
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "interop"))
import sim_arm as S  # noqa: E402  (first: it sets CYCLONEDDS_URI before cyclonedds is loaded)
from harness import check, dds_domain, exit_code, wait_for  # noqa: E402
from saw_run import SawRt, arm_ready  # noqa: E402
from sawdds import Client, msgs  # noqa: E402

JOINTS = "{names: [x, y, z, rx, ry, rz], min: [-0.2, -0.2, -0.3, -3.2, -3.2, -3.2], " \
         "max: [0.2, 0.2, 0.1, 3.2, 3.2, 3.2]}"


def deployment(tag, domain, kind, arm, commands):
    device = f"{arm.lower()}{tag}"
    extra = (f"workspace: {{min: [-0.2, -0.2, -0.3], max: [0.2, 0.2, 0.1]}}\n      joints: {JOINTS}"
             if kind == "psm" else "joints: " + JOINTS)
    # No timing verdict here (the drive tests have those): under a sanitizer a stall must not fault
    # the device before the moves are tried, so time is not judged and staleness is loose.
    return device, f"""deployment: {{name: moves{tag}, clock: real, deadline: off}}
components:
  - name: {device}
    type: dvrk_arm
    task: {{period: 1ms, priority: 80}}
    params:
      kind: {kind}
      home: true
      start_enabled: true
      stale_timeout: 1s
      {extra}
connections:
  - {{client: {device}, required: dvrk, server: {arm}_dds{tag}, provided: dvrk}}
exports:
  - {{component: {device}, provided: arm}}
record:
  columns: [{device}.operating_state, {device}.measured_cp]
gateway:
  domain: {domain}
  import:
    - {{component: {arm}_dds{tag}, arm: {arm}, commands: [{", ".join(commands)}], command_timeout: 50ms}}
"""


def start(saw_rt, work, name, text):
    path = os.path.join(work, f"{name}.yaml")
    with open(path, "w") as f:
        f.write(text)
    return SawRt(saw_rt, path, os.path.join(work, f"{name}.csv"))


def pose(p):
    return msgs.PoseStamped(pose=msgs.Pose(position=msgs.Point(x=p[0], y=p[1], z=p[2]),
                                           orientation=msgs.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)))


def joints(q):
    return msgs.JointState(position=list(q))


def arrives(sim, goal, timeout=5.0, tolerance=2e-4):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        p = sim.position()
        if max(abs(a - b) for a, b in zip(p, goal)) < tolerance and not sim.operating_state()[2]:
            return True
        time.sleep(0.02)
    return False


@contextmanager
def enabled_by(saw_rt, work, name, text, sim, what):
    """saw-rt running `text`, once it enabled and homed `sim` (None if it did not: said); stopped
    with SIGTERM at the end (a killed one stays killed)."""
    rt = start(saw_rt, work, name, text)
    try:
        ok = check(arm_ready(sim), f"saw-rt enabled and homed the simulated {what}")
        if not ok:
            print(rt.text())
        yield rt if ok else None
    finally:
        rt.stop()


def psm_moves(saw_rt, work, tag, domain):
    print("-- (a) a PSM's move_cp and move_jp, checked by the device")
    no_cut = S.Params(refuse_when_busy=False)
    with S.SimArm("PSM1", domain, kind="psm", rate=500.0, params=no_cut) as sim:
        device, text = deployment(tag, domain, "psm", "PSM1", ["servo_cp", "move_cp", "move_jp", "hold"])
        with enabled_by(saw_rt, work, "psm", text, sim, "PSM") as rt:
            if rt is None:
                return
            c = Client(domain)
            topic = f"rt/{device}/"
            home = sim.position()
            refused = [(-0.5, 0.0, -0.1), (0.0, 0.0, 0.5)]  # outside the device's workspace
            for p in refused:
                c.send(topic + "move_cp", pose(p))
            goal = (home[0] + 0.02, home[1] - 0.01, home[2])
            t = time.monotonic()
            c.send(topic + "move_cp", pose(goal))
            got = sim.wait_command("move_cp", timeout=5.0, since=t - 1.0)
            check(got is not None and abs(got.value.pose.position.x - goal[0]) < 1e-9,
                  "move_cp reached the arm (the goal inside the workspace)")
            early = [x for x in sim.commands("move_cp") if abs(x.value.pose.position.x) > 0.4 or
                     x.value.pose.position.z > 0.4]
            check(not early, f"the two goals outside the workspace never reached it ({len(early)} did)")
            check(arrives(sim, goal), f"the arm planned the move and arrived: {sim.position()} vs {goal}")
            check(not [x for x in sim.commands(since=t) if x.topic == "hold"],
                  "nothing of ours cut the move short (no hold)")
            js = wait_for(c.reader(topic + "measured_js"), lambda s: len(s.position) == 6, 5)
            check(js is not None and list(js.name) == list(S.JOINT_NAMES),
                  f"measured_js is the device's, its joints named: {list(js.name) if js else None}")
            q = (goal[0] - 0.03, goal[1], goal[2], 0.0, 0.0, 0.0)
            c.send(topic + "move_jp", joints((0.0, 0.0, 0.0, 0.0, 0.0, 4.0)))  # over rz's limit
            t = time.monotonic()
            c.send(topic + "move_jp", joints(q))
            got = sim.wait_command("move_jp", timeout=5.0, since=t - 1.0)
            check(got is not None and abs(got.value.position[0] - q[0]) < 1e-9, "move_jp reached the arm")
            check(len(sim.commands("move_jp")) == 1, "the goal over a joint limit never reached it")
            check(arrives(sim, q[:3]), f"and the arm arrived: {sim.position()} vs {q[:3]}")


def kill_during_move(saw_rt, work, tag, domain):
    print("-- (b) kill -9 of saw-rt during a move")
    slow = S.Params(refuse_when_busy=False, move_speed=0.02)
    with S.SimArm("PSM1", domain, kind="psm", rate=500.0, params=slow) as sim:
        device, text = deployment(tag, domain, "psm", "PSM1", ["servo_cp", "move_cp", "move_jp", "hold"])
        with enabled_by(saw_rt, work, "kill", text, sim, "PSM") as rt:
            if rt is None:
                return
            c = Client(domain)
            home = sim.position()
            goal = (home[0] + 0.1, home[1], home[2])  # 5 s at 2 cm/s
            c.send(f"rt/{device}/move_cp", pose(goal))
            if not check(sim.wait_command("move_cp", timeout=5.0) is not None, "the move reached the arm"):
                return
            time.sleep(0.5)  # the arm under way
            t = time.monotonic()
            rt.p.kill()
            hold = sim.wait_command("hold", timeout=2.0, since=t)
            check(hold is not None, "hold reached the arm after the kill")
            if hold is not None:
                print(f"figure: kill -9 of saw-rt during a move to hold at the arm: {(hold.time - t) * 1000:.0f} ms")
            time.sleep(0.3)
            stopped = sim.position()
            time.sleep(0.3)
            check(math.dist(stopped, sim.position()) < 1e-4 and math.dist(stopped, goal) > 0.05,
                  f"the arm stopped short of the goal ({math.dist(stopped, goal) * 100:.1f} cm away) and stays")
            check(rt.wait_line("exiting while its client moved the arm", 5.0) is not None, "the gateway said why")


def mtm_free_and_wrench(saw_rt, work, tag, domain):
    print("-- (c) an MTM's free and measured_cf")
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0) as sim:
        device, text = deployment(tag, domain, "mtm", "MTML", ["servo_cf", "free"])
        with enabled_by(saw_rt, work, "mtm", text, sim, "MTM") as rt:
            if rt is None:
                return
            c = Client(domain)
            topic = f"rt/{device}/"
            cf = wait_for(c.reader(topic + "measured_cf"), lambda s: True, 5)
            check(cf is not None, "the MTM's body/measured_cf is the device's measured_cf")
            t = time.monotonic()
            c.send(topic + "free", msgs.Empty())
            check(sim.wait_command("free", timeout=5.0, since=t - 1.0) is not None, "free reached the arm")
            rc = rt.stop(signal.SIGTERM)
            check(rc == 0, f"saw-rt stopped in order (exit {rc})")
            later = [x.topic for x in sim.commands(since=t) if x.topic != "free"]
            check(not [x for x in later if x != "use_gravity_compensation"],
                  f"after free, nothing of ours was left to undo: nothing else sent ({later})")


def main(saw_rt):
    tag = str(os.getpid())
    domain = dds_domain()
    work = tempfile.mkdtemp()
    psm_moves(saw_rt, work, tag, domain)
    kill_during_move(saw_rt, work, tag, domain)
    mtm_free_and_wrench(saw_rt, work, tag, domain)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
