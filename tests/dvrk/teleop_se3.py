"""saw-rt teleoperates the independent simulated dVRK PSM from the independent simulated MTM in SE(3)
(sim_arm.py, Cyclone DDS), deployed by the shipped config/dvrk-mtm-psm.yaml (renamed for this run,
on this test's DDS domain): the `surgical` law on the MTM's read-only import and the PSM's
`dvrk_arm` device.

(a) the PSM follows the scripted hand on the MTM: ±3 cm along x and ±20° about z at 0.5 Hz,
    scaled 0.2 in translation, absolute in orientation; its jaw follows the MTM's gripper; the
    translation (mm) and orientation (degrees) tracking errors are printed and bounded;
(b) the console's clutch: no goal while pressed, and at the release no step in the commanded
    pose (the largest step of the commanded pose at engagement and release is printed);
(c) a PSM turned 40° from the MTM: the law does not engage (`aligned` 0, `misalignment` printed)
    and the PSM is not moved;
(d) the console's operator_present (the shipped file says needs_operator): no goal moves before
    the operator is present, none while away, and no step at each return;
(e) the camera frame from an ECM (a third simulated arm, imported read-only and connected to the
    teleoperation's `camera` interface, as the shipped file's comment says): the ECM rolled 90°
    about z, the hand's x moves the PSM along y, not x;
(f) the MTM as an RT `dvrk_arm` device that takes move_cp (as the shipped file's comment says),
    40° from the PSM, powered and homed by the console: the law sends it one move_cp, at its
    position turned to the PSM's orientation, and no wrench until the arm is busy with it; the
    law engages once it is idle there, and the PSM's goals make no step; the time to align is
    printed.

Each check is printed; the exit code is 1 if any failed. A phase in which the simulated arms
stalled (a Python process starved on a loaded machine: the PSM's device FAULTs "stale: the dVRK
stopped publishing", or a task its deadline) gives no verdict if the PSM was then held, as the
device must; it is run again, up to three times, and a phase stalled in all three fails.

usage: teleop_se3.py SAW_RT
"""
import csv
from contextlib import contextmanager
import math
import os
import re
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "interop"))
import sim_arm as S  # noqa: E402  (first: it sets CYCLONEDDS_URI before cyclonedds is loaded)
import harness  # noqa: E402
from harness import check, dds_domain, exit_code  # noqa: E402
from saw_run import SawRt, arm_ready, shipped  # noqa: E402

NAMES = ("psm1", "psm_teleop", "PSM1_dds", "MTML_dds", "ECM_dds", "dvrk-mtm-psm")
HAND = (0.03, 0.5, (1.0, 0.0, 0.0), math.radians(20))
STALL = re.compile(r"FAULT.*(stopped publishing|deadline missed)")


def stalled(rt, psm, stopped):
    """The first FAULT line of a stall in this run, or None; a stall whose PSM was not held after
    it (before saw-rt was stopped at `stopped`, whose exit holds it too) is a failure of its own:
    the device must reach its safe state whatever the cause."""
    at = next(((t, line) for t, line in list(rt.lines) if STALL.search(line)), None)
    if at is None:
        return None
    held = [c for c in psm.commands("hold", since=at[0] - 1.0) if c.time < min(stopped, at[0] + 1.0)]
    check(held, f"after the stall the PSM was held: {at[1].strip()}")
    return at[1].strip()


@contextmanager
def running(rt, psm, run):
    """A phase's checks while saw-rt runs: then nothing faulted (a stall aside, which `attempted`
    judges), and saw-rt is stopped whatever happened, the run's stall noted."""
    try:
        yield
        early = rt.faults_before(time.monotonic())
        check(not early, f"nothing faulted: {early[:2]}")
    finally:
        stopped = time.monotonic()
        rt.stop()
        run["stall"] = stalled(rt, psm, stopped)


def attempted(phase, *args):
    """Runs phase(*args, run) until a run gives a verdict (the phase sets run["stall"]); a stalled
    run whose checks all held is one."""
    def once():
        before, run = len(harness.failures), {}
        phase(*args, run)
        return run.get("stall") if len(harness.failures) > before else None
    harness.until_no_stall(once, phase.__name__)


MTM_DEVICE = """  - name: mtml{tag}
    type: dvrk_arm
    task: {{period: 1ms, priority: 80, offset: 600us}}
    params: {{kind: mtm, safe_command: hold, home: true, start_enabled: true, stale_timeout: 50ms}}

"""


def start(saw_rt, work, tag, domain, name, ecm=False, mtm_device=False):
    text = shipped("dvrk-mtm-psm.yaml", tag, domain, NAMES)
    if mtm_device:  # the MTM as an RT device that takes move_cp, as the shipped file's comment says
        text = text.replace("  - name: psm_teleop", MTM_DEVICE.format(tag=tag) + "  - name: psm_teleop", 1)
        text = text.replace(f"server: MTML_dds{tag}, provided: arm}}",
                            f"server: mtml{tag}, provided: arm}}\n"
                            f"  - {{client: mtml{tag}, required: dvrk, server: MTML_dds{tag}, provided: dvrk}}", 1)
        text = text.replace(f"- {{component: MTML_dds{tag}, arm: MTML}}",
                            f"- {{component: MTML_dds{tag}, arm: MTML, commands: [servo_cf, move_cp, hold], "
                            f"command_timeout: 50ms, offset: 800us}}", 1)
    if ecm:  # the ECM's import on the teleoperation's camera interface, as the file's comment says
        text = text.replace("\nconnections:\n", f"\nconnections:\n  - {{client: psm_teleop{tag}, required: camera, "
                            f"server: ECM_dds{tag}, provided: arm}}\n", 1)
        text = text.replace("  import:\n", f"  import:\n    - {{component: ECM_dds{tag}, arm: ECM}}\n", 1)
    path = os.path.join(work, f"{name}.yaml")
    with open(path, "w") as f:
        f.write(text)
    return SawRt(saw_rt, path, os.path.join(work, f"{name}.csv"))


def when_ready(psm):
    """The PSM enabled, homed and idle: the gateway's readers of the console have matched by then
    (a press before that is not seen: the pedals are not latched)."""
    return check(arm_ready(psm), f"the PSM is enabled and homed: {psm.operating_state()}")


def goals(sim, since=0.0):
    return [c for c in sim.commands("servo_cp", since=since)]


def position(c):
    p = c.value.pose.position
    return (p.x, p.y, p.z)


def yaw(c):
    q = c.value.pose.orientation
    return math.degrees(2.0 * math.atan2(q.z, q.w))


def goals_move(psm, first):
    """The first goal more than 0.1 mm from `first` (the law engaged: the hand drives it), or None
    after 10 s."""
    p0 = position(first) if first else (0.0, 0.0, 0.0)
    return psm.wait_command("servo_cp", pred=lambda v: math.dist(
        (v.pose.position.x, v.pose.position.y, v.pose.position.z), p0) > 1e-4, timeout=10.0)


def largest_step(cmds):
    return max((math.dist(position(a), position(b)) for a, b in zip(cmds, cmds[1:])), default=0.0)


def follow_and_clutch(saw_rt, work, tag, domain, run):
    print("-- (a) the PSM follows the MTM in SE(3); (b) the clutch")
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0, console=True, hand=HAND) as mtm, \
            S.SimArm("PSM1", domain, kind="psm", rate=500.0) as psm:
        rt = start(saw_rt, work, tag, domain, "follow")
        with running(rt, psm, run):
            when_ready(psm)
            mtm.press("operator_present")
            first = psm.wait_command("servo_cp", timeout=30.0)
            if not check(first is not None, "the teleoperation drives the simulated PSM (a servo_cp arrived)"):
                print(rt.text())
                return
            # Held until the hand's turn passes within align_tolerance of the PSM's: engaged once
            # the goals move.
            if not check(goals_move(psm, first) is not None, "the law engages and the goals move"):
                print(rt.text())
                return
            t0 = time.monotonic()
            time.sleep(3.0)  # one and a half periods of the hand
            seen = goals(psm, since=t0)
            xs = [position(c)[0] for c in seen]
            yaws = [yaw(c) for c in seen]
            swing, turn = max(xs) - min(xs), max(yaws) - min(yaws)
            check(0.009 < swing < 0.015, f"the PSM's goal swings 0.2 × the hand's ±3 cm: {swing * 1000:.1f} mm")
            check(30 < turn < 45, f"and turns with the hand's ±20°: {turn:.1f}°")
            check(largest_step(seen) < 0.001, f"no step in the goals: largest {largest_step(seen) * 1000:.3f} mm")
            jaws = [c.value.position[0] for c in psm.commands("jaw/servo_jp", since=t0)]
            check(jaws and max(jaws) - min(jaws) > 0.2,
                  f"the jaw follows the MTM's gripper (0.5 ± 0.2 rad): {min(jaws):.2f}..{max(jaws):.2f}"
                  if jaws else "the jaw follows the MTM's gripper: no jaw goal")
            t_press = time.monotonic()
            mtm.press("clutch")
            time.sleep(0.5)
            during = goals(psm, since=t_press + 0.1)
            check(not during, f"clutched: no goal ({len(during)} sent)")
            last = goals(psm)[-1]
            t_release = time.monotonic()
            mtm.release("clutch")
            time.sleep(1.0)
            after = goals(psm, since=t_release)
            step = math.dist(position(after[0]), position(last)) if after else float("nan")
            check(after and step < 0.001, f"released: the goals start where they stopped (step {step * 1000:.3f} mm)")
            if after:
                print(f"figure: largest commanded-pose step at the clutch's release: {step * 1000:.3f} mm, "
                      f"{abs(yaw(after[0]) - yaw(last)):.2f}°")
        # The law's goals, bursts of the MTM's stream and the clutch's release included, are
        # within the PSM device's own step checks. After the PSM's commands stopped (the clutch; a
        # stall), the law engages afresh where it holds; a goal sent in the same cycle as the
        # device's trip may still be refused: at most two a trip.
        out = rt.text()
        refused = re.search(r"psm1\d+: (\d+) servo commands refused", out)
        trips = re.search(r"psm1\d+: commands stopped (\d+) times", out)
        n, t = int(refused.group(1)) if refused else 0, int(trips.group(1)) if trips else 0
        check(n <= 2 * t, f"the PSM refused {n} of the law's goals, its commands stopped {t} times")
        rows = [r for r in csv.DictReader(open(os.path.join(work, "follow.csv")))
                if r[f"psm_teleop{tag}.operating_state"] == "ENABLED" and r[f"psm_teleop{tag}.aligned"] == "1"
                and r[f"psm_teleop{tag}.clutched"] == "0" and r[f"psm_teleop{tag}.operator_present"] == "1"]
        if check(len(rows) > 1000, f"the record has the law engaged ({len(rows)} cycles)"):
            e = sorted(float(r[f"psm_teleop{tag}.tracking_error"]) for r in rows)
            o = sorted(float(r[f"psm_teleop{tag}.orientation_error"]) for r in rows)
            rms = (sum(x * x for x in e) / len(e)) ** 0.5
            orms = (sum(x * x for x in o) / len(o)) ** 0.5
            print(f"figure: MTM → PSM in SE(3), scale 0.2 ({len(e)} cycles): translation RMS {rms * 1000:.2f} mm "
                  f"(max {e[-1] * 1000:.2f}), orientation RMS {orms:.2f}° (max {o[-1]:.2f}°) — the sim's lag included")
            # The sim's lag dominates (0.4–0.7 mm, 1.2–1.9° seen with a CPU hog beside it): the
            # bound is what a law that does not follow fails (orientation held: 14° RMS, the
            # hand's own), and goals refused by the PSM failed (3 mm, 9°).
            check(rms < 0.002 and orms < 5.0, "tracking within 2 mm and 5° RMS")


def misaligned(saw_rt, work, tag, domain, run):
    print("-- (c) a misaligned master does not engage")
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0, console=True) as mtm, \
            S.SimArm("PSM1", domain, kind="psm", rate=500.0) as psm:
        mtm.home_q = (0.0, 0.0, math.sin(math.radians(20)), math.cos(math.radians(20)))  # 40° about z
        mtm.set_hand((0.03, 0.5, (1.0, 0.0, 0.0), 0.0))  # moving, but turned away from the PSM
        rt = start(saw_rt, work, tag, domain, "misaligned")
        with running(rt, psm, run):
            when_ready(psm)
            mtm.press("operator_present")
            if not check(psm.wait_command("servo_cp", timeout=30.0) is not None, "the PSM gets goals (held)"):
                print(rt.text())
                return
            t0 = time.monotonic()
            time.sleep(2.0)
            seen = goals(psm, since=t0)
            xs = [position(c)[0] for c in seen]
            check(seen and max(xs) - min(xs) < 1e-9, "the PSM is held where it was while the MTM moves")
        rows = list(csv.DictReader(open(os.path.join(work, "misaligned.csv"))))
        off = [float(r[f"psm_teleop{tag}.misalignment"]) for r in rows
               if r[f"psm_teleop{tag}.operating_state"] == "ENABLED"]
        engaged = [r for r in rows if r[f"psm_teleop{tag}.aligned"] == "1"]
        check(off and not engaged and abs(off[-1] - 40) < 1,
              f"not engaged, the operator told the master is {off[-1]:.1f}° off" if off else "no ENABLED row")


def operator_present(saw_rt, work, tag, domain, run):
    print("-- (d) the operator's presence")
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0, console=True, hand=HAND) as mtm, \
            S.SimArm("PSM1", domain, kind="psm", rate=500.0) as psm:
        rt = start(saw_rt, work, tag, domain, "operator")
        with running(rt, psm, run):
            # Once the PSM is enabled, homed and idle, the law could drive it: give it a while.
            when_ready(psm)
            time.sleep(1.0)
            early = goals(psm)
            xs = [position(c)[0] for c in early]
            check(not xs or max(xs) - min(xs) < 1e-9, f"no operator: no goal moves ({len(early)} held goals)")
            steps = []
            for k in range(2):
                t_in = time.monotonic()
                last = goals(psm)[-1] if goals(psm) else None
                mtm.press("operator_present")
                time.sleep(1.5)
                after = goals(psm, since=t_in)
                moved = [position(c)[0] for c in after]
                check(len(moved) > 100 and max(moved) - min(moved) > 0.002,
                      f"present ({k + 1}): the PSM follows ({len(after)} goals)")
                if last is not None and after:
                    steps.append(math.dist(position(after[0]), position(last)))
                t_out = time.monotonic()
                mtm.release("operator_present")
                time.sleep(0.5)
                away = goals(psm, since=t_out + 0.1)
                check(not away, f"away ({k + 1}): no goal ({len(away)} sent)")
            if steps:
                print(f"figure: largest commanded-pose step at the operator's return: {max(steps) * 1000:.3f} mm")
                check(max(steps) < 0.001, f"no step at the operator's return ({max(steps) * 1000:.3f} mm)")


def camera_from_ecm(saw_rt, work, tag, domain, run):
    print("-- (e) the camera frame from an ECM")
    roll = (0.0, 0.0, math.sin(math.radians(45)), math.cos(math.radians(45)))  # 90° about z
    # The PSM turned as the camera is: the MTM (identity) is then aligned with it in the camera's frame.
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0, console=True,
                  hand=(0.03, 0.5, (1.0, 0.0, 0.0), 0.0)) as mtm, \
            S.SimArm("PSM1", domain, kind="psm", rate=500.0, home_q=roll) as psm, \
            S.SimArm("ECM", domain, kind="ecm", rate=100.0, home_q=roll, start=(0.0, 0.0, -0.1)):
        rt = start(saw_rt, work, tag, domain, "camera", ecm=True)
        with running(rt, psm, run):
            when_ready(psm)
            mtm.press("operator_present")
            first = psm.wait_command("servo_cp", timeout=30.0)
            if not check(goals_move(psm, first) is not None, "the law engages in the ECM's frame and the goals move"):
                print(rt.text())
                return
            t0 = time.monotonic()
            time.sleep(2.5)
            seen = goals(psm, since=t0)
            xs, ys = [position(c)[0] for c in seen], [position(c)[1] for c in seen]
            along_y, along_x = max(ys) - min(ys), max(xs) - min(xs)
            print(f"figure: through the ECM rolled 90°, the hand's ±3 cm along x moves the PSM "
                  f"{along_y * 1000:.2f} mm along y and {along_x * 1000:.3f} mm along x")
            check(0.009 < along_y < 0.015 and along_x < 0.0005,
                  "the hand's x is the camera's: the PSM moves along y, not x")


def aligned_by_move(saw_rt, work, tag, domain, run):
    print("-- (f) a misaligned MTM brought to the PSM's orientation by move_cp")
    turned = (0.0, 0.0, math.sin(math.radians(20)), math.cos(math.radians(20)))  # 40° about z
    with S.SimArm("MTML", domain, kind="mtm", rate=500.0, console=True, home_q=turned) as mtm, \
            S.SimArm("PSM1", domain, kind="psm", rate=500.0) as psm:
        mtm.powered_and_homed()
        rt = start(saw_rt, work, tag, domain, "align", mtm_device=True)
        with running(rt, psm, run):
            when_ready(psm)
            t_present = time.monotonic()
            mtm.press("operator_present")
            move = mtm.wait_command("move_cp", timeout=30.0, since=t_present - 0.1)
            if not check(move is not None, "the law sent the misaligned MTM a move_cp"):
                print(rt.text())
                return
            q = move.value.pose.orientation
            off = math.degrees(2.0 * math.acos(min(1.0, abs(q.w))))  # from the PSM's (identity)
            at = math.dist(position(move), mtm.position())
            check(off < 0.01 and at < 0.002,
                  f"to the PSM's orientation ({off:.3f}° from it), at the MTM's position ({at * 1000:.2f} mm)")
            wrench = [c for c in mtm.commands("body/servo_cf", since=move.time) if c.time < move.time + 0.05]
            check(not wrench, f"no wrench reached the MTM while its move began ({len(wrench)})")
            deadline = time.monotonic() + 10.0  # busy while it turns, then idle: the law engages
            while time.monotonic() < deadline and (mtm.operating_state()[2] or time.monotonic() < move.time + 0.2):
                time.sleep(0.05)
            time.sleep(1.0)
            moves = mtm.commands("move_cp")
            check(len(moves) == 1, f"one move_cp ({len(moves)} sent)")
            seen = goals(psm, since=t_present)
            yaws = [yaw(c) for c in seen]
            check(seen and largest_step(seen) < 1e-4 and max(yaws) - min(yaws) < 0.1,
                  f"the PSM's goals made no step ({largest_step(seen) * 1000:.3f} mm, "
                  f"{max(yaws) - min(yaws) if yaws else 0:.3f}°)")
        rows = [r for r in csv.DictReader(open(os.path.join(work, "align.csv")))
                if r[f"psm_teleop{tag}.operating_state"] == "ENABLED" and r[f"psm_teleop{tag}.operator_present"] == "1"]
        engaged = [r for r in rows if r[f"psm_teleop{tag}.aligned"] == "1"]
        if check(rows and engaged, "the law engaged once the MTM was aligned"):
            first_off = float(rows[0][f"psm_teleop{tag}.misalignment"])
            took = float(engaged[0]["time"]) - float(rows[0]["time"])
            print(f"figure: time to align by move_cp: {took:.2f} s from the operator's press "
                  f"(the MTM {first_off:.1f}° off; the simulated arm's trajectory included)")
            check(abs(first_off - 40) < 1 and took < 5.0, "from 40° off, aligned within 5 s")


def main(saw_rt):
    tag = str(os.getpid())
    domain = dds_domain()
    work = tempfile.mkdtemp()
    attempted(follow_and_clutch, saw_rt, work, tag, domain)
    attempted(misaligned, saw_rt, work, tag, domain)
    attempted(operator_present, saw_rt, work, tag, domain)
    attempted(camera_from_ecm, saw_rt, work, tag, domain)
    attempted(aligned_by_move, saw_rt, work, tag, domain)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
