"""saw-rt drives the independent simulated dVRK MTM (sim_arm.py, Cyclone DDS) as the slave of a
simulated Omni — the paper's "da Vinci master as a slave" — through its gateway's read-write import
(`gateway: import: [{commands: [servo_cf, hold]}]`) and the RT `dvrk_arm` device, deployed by the
shipped config/dvrk-mtm-slave.yaml (renamed for this run, on this test's DDS domain):

(a) the handshake: `enable`, then `home`, then gravity compensation, and no motion command before
    the arm is ENABLED, homed and not busy (the simulated arm warns of every early one);
(b) force feedback: the MTM follows the Omni's scripted hand under body/servo_cf; tracking error
    and the latency from the teleoperation's cycle to the wrench's arrival are printed;
(c) every stop path leaves a zero wrench on the arm, which otherwise keeps its last one for ever:
    saw-rt's SIGTERM (the device's safe command), `kill -9` of saw-rt (the gateway's exit path,
    through its PDEATHSIG), saw-rt frozen (SIGSTOP: the import's own watchdog);
(d) each way the arm goes wrong is the device's FAULT naming it, with the zero wrench: its
    stream stops, or goes on stamped 0 (the dVRK's invalid data) or with one stamp repeated (stale
    by its header stamps, as by arrival), it reports an error (its words in saw-rt's log), it
    faults.

Each check is printed; the exit code is 1 if any failed. Waits are polls with a bound.

usage: drive_mtm.py SAW_RT
"""
import csv
import os
import signal
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "interop"))
import sim_arm as S  # noqa: E402  (first: it sets CYCLONEDDS_URI before cyclonedds is loaded)
from harness import check, dds_domain, exit_code  # noqa: E402
from saw_run import SawRt, shipped  # noqa: E402

ARM = "MTML"
WRENCH = "body/servo_cf"


NAMES = ("sim_master", "mtml", "mtm_teleop", "MTML_dds", "dvrk-mtm-slave")


def nonzero(w):
    f = w.wrench.force
    return abs(f.x) + abs(f.y) + abs(f.z) > 0


def following(sim, since=0.0, timeout=30.0):
    """The first non-zero wrench the arm received (the teleoperation drives it), or None."""
    return sim.wait_command(WRENCH, nonzero, timeout=timeout, since=since)


def zero_after(sim, t, timeout):
    """The first zero wrench received after time t, or None."""
    return sim.wait_command(WRENCH, lambda w: not nonzero(w), timeout=timeout, since=t)


def last_wrench_is_zero(sim):
    got = sim.commands(WRENCH)
    return bool(got) and not nonzero(got[-1].value) and sim.stored_wrench() == (0.0, 0.0, 0.0)


def wrench_story(sim, t):
    """The last wrenches the arm received, timed from t, and the one it keeps: what a failure saw."""
    got = sim.commands(WRENCH)[-6:]
    rows = [f"  {(c.time - t) * 1000:+8.1f} ms  {c.value.wrench.force.x:+.4f} {c.value.wrench.force.y:+.4f} "
            f"{c.value.wrench.force.z:+.4f}" for c in got]
    return "\n".join(["the last wrenches at the arm (ms from the stop):"] + rows +
                      [f"  the arm keeps {sim.stored_wrench()}"])


def start(saw_rt, work, tag, domain, name):
    path = os.path.join(work, f"{name}.yaml")
    with open(path, "w") as f:
        f.write(shipped("dvrk-mtm-slave.yaml", tag, domain, NAMES))
    return SawRt(saw_rt, path, os.path.join(work, f"{name}.csv"))


def driven(saw_rt, work, tag, domain, name, sim):
    """saw-rt started and driving the arm, or None (said, and stopped)."""
    rt = start(saw_rt, work, tag, domain, name)
    if following(sim) is not None:
        return rt
    check(False, f"{name}: the teleoperation drives the simulated MTM first")
    print(rt.text())
    rt.stop()
    return None


def handshake_and_follow(saw_rt, work, tag, domain):
    print("-- (a) handshake, (b) force feedback, (c) SIGTERM")
    with S.SimArm(ARM, domain, kind="mtm", rate=500.0) as sim:
        rt = start(saw_rt, work, tag, domain, "follow")
        first = following(sim)
        check(first is not None, "the teleoperation drives the simulated MTM (a non-zero body/servo_cf arrived)")
        if first is None:
            print(rt.text())
            rt.stop()
            return
        # The run's length, not a wait for a result: the hand makes one sinusoid period (2 s).
        xs = []
        t_end = time.monotonic() + 3.0
        while time.monotonic() < t_end:
            xs.append(sim.position()[0])
            time.sleep(0.01)
        seen = sim.commands()
        states = [c for c in seen if c.topic == "state_command"]
        # An enable or home repeated is the device's retry of one with no effect after 1 s (a slow
        # match under load): the order is what is judged.
        order = [x for i, x in enumerate(c.value.string for c in states)
                 if i == 0 or x != states[i - 1].value.string]
        check(order[:2] == ["enable", "home"],
              f"the device sent enable, then home: {[c.value.string for c in states]}")
        first_motion = next((c for c in seen if c.topic in (WRENCH, "servo_cp", "hold")), None)
        home = next((c for c in states if c.value.string == "home"), None)
        check(first_motion is not None and home is not None and first_motion.time > home.time,
              "no motion command before home was asked")
        gravity = next((c for c in seen if c.topic == "use_gravity_compensation"), None)
        check(gravity is not None and gravity.value.data and gravity.time < first.time,
              "gravity compensation turned on before the first wrench")
        early = [w for w in sim.warnings() if "not ready" in w or "busy" in w]
        check(not early, f"no command reached the arm before it was ENABLED, homed and idle: {early[:3]}")
        swing = max(xs) - min(xs)
        check(swing > 0.03, f"the MTM follows the Omni's hand (±3 cm): it swung {swing * 100:.1f} cm")

        t_stop = time.monotonic()
        # What follows is a verdict on the SIGTERM path only if nothing faulted before it.
        early = rt.faults_before(t_stop)
        check(not early, f"nothing faulted before the SIGTERM: {early[:2]}")
        rc = rt.stop(signal.SIGTERM)
        check(rc == 0, f"saw-rt stopped in order on SIGTERM (exit {rc})")
        z = zero_after(sim, t_stop, 2.0)
        if not check(z is not None and last_wrench_is_zero(sim),
                     "SIGTERM: the last wrench on the arm is zero (the device's safe command, or the import's as it exits)"):
            print(wrench_story(sim, t_stop))
            print(rt.text())
        report_figures(os.path.join(work, "follow.csv"), tag, seen)


def report_figures(record, tag, seen):
    rows = list(csv.DictReader(open(record)))
    t = f"mtm_teleop{tag}"
    state, fx = f"{t}.operating_state", f"{t}.slave_force.x"
    enabled = [r for r in rows if r[state] == "ENABLED"]
    if not enabled or fx not in rows[0]:
        check(False, f"the record has the teleoperation ENABLED and its slave force ({len(enabled)} rows)")
        return
    errors = sorted(float(r[f"{t}.tracking_error"]) for r in enabled)
    rms = (sum(e * e for e in errors) / len(errors)) ** 0.5
    print(f"figure: tracking error while ENABLED ({len(enabled)} cycles): RMS {rms * 1000:.2f} mm, "
          f"max {errors[-1] * 1000:.2f} mm")
    check(rms < 0.01, f"tracking error RMS {rms * 1000:.2f} mm < 10 mm")
    # Latency: a teleoperation cycle's slave force, found again in the wrench that reached the arm.
    times = [float(r["time"]) for r in enabled]
    forces = [(float(r[fx]), float(r[f"{t}.slave_force.y"]), float(r[f"{t}.slave_force.z"]))
              for r in enabled]
    lat = []
    j = 0
    for c in seen:
        if c.topic != WRENCH or not nonzero(c.value):
            continue
        f = c.value.wrench.force
        while j < len(times) and times[j] < c.time - 0.2:
            j += 1
        for k in range(j, len(times)):
            if times[k] > c.time:
                break
            if max(abs(forces[k][0] - f.x), abs(forces[k][1] - f.y), abs(forces[k][2] - f.z)) < 1e-6:
                lat.append(c.time - times[k])
                break
    if len(lat) < 100:
        check(False, f"the teleoperation's forces found again at the arm: only {len(lat)}")
        return
    lat.sort()
    print(f"figure: latency from the teleoperation's cycle to the wrench at the arm ({len(lat)} matched): "
          f"median {lat[len(lat) // 2] * 1000:.2f} ms, p99 {lat[int(len(lat) * 0.99)] * 1000:.2f} ms, "
          f"max {lat[-1] * 1000:.2f} ms")


def kill_paths(saw_rt, work, tag, domain):
    print("-- (c) kill -9 of saw-rt: the gateway's exit path")
    with S.SimArm(ARM, domain, kind="mtm", rate=500.0) as sim:
        rt = driven(saw_rt, work, tag, domain, "kill", sim)
        if rt is None:
            return
        t_kill = time.monotonic()
        rt.p.kill()
        z = zero_after(sim, t_kill, 2.0)
        check(z is not None, "kill -9 of saw-rt: a zero wrench reached the arm (from its orphaned gateway)")
        if z is not None:
            print(f"figure: kill -9 of saw-rt to the zero wrench at the arm: {(z.time - t_kill) * 1000:.0f} ms")
            check(z.time - t_kill < 0.4, "within 400 ms")
        said = rt.wait_line("exiting while its client moved the arm", 5.0)
        check(said is not None, "the gateway said why it sent it")
        time.sleep(0.3)  # anything sent after the zero wrench would arrive by now (bounded, not hoped)
        check(last_wrench_is_zero(sim), "and nothing came after it")
        rt.stop(signal.SIGKILL)

    print("-- (c) saw-rt frozen (SIGSTOP): the import's watchdog")
    with S.SimArm(ARM, domain, kind="mtm", rate=500.0) as sim:
        rt = driven(saw_rt, work, tag, domain, "stop", sim)
        if rt is None:
            return
        t_stop = time.monotonic()
        os.kill(rt.p.pid, signal.SIGSTOP)
        z = zero_after(sim, t_stop, 2.0)
        check(z is not None, "saw-rt frozen: a zero wrench reached the arm (the import's watchdog)")
        if z is not None:
            print(f"figure: saw-rt frozen to the zero wrench at the arm: {(z.time - t_stop) * 1000:.0f} ms "
                  f"(the import's command_timeout: 50 ms)")
            check(z.time - t_stop < 0.3, "within 300 ms")
        check(rt.wait_line("its client sent nothing for 50 ms", 5.0) is not None, "the gateway said why")
        os.kill(rt.p.pid, signal.SIGCONT)
        rc = rt.stop(signal.SIGTERM)
        check(rc == 0, f"saw-rt, woken, stopped in order (exit {rc})")
        check(last_wrench_is_zero(sim), "the last wrench on the arm is zero")


def arm_faults(saw_rt, work, tag, domain):
    # The stream stops; it goes on stamped 0 (the dVRK's invalid data); it repeats one stamp; the arm
    # faults.
    for name, act, needle in (("stale", lambda s: s.pause_publishing(), "stale"),
                              ("invalid stamps", lambda s: s.set_invalid_stamps(True), "stale"),
                              ("frozen stamps", lambda s: s.freeze_stamps(True), "stale"),
                              ("error", lambda s: s.report_error("simulated tracking error"), "reported an error"),
                              ("fault", lambda s: s.fault("simulated encoder error"), "in FAULT")):
        print(f"-- (d) the arm goes wrong: {name}")
        with S.SimArm(ARM, domain, kind="mtm", rate=500.0) as sim:
            rt = driven(saw_rt, work, tag, domain, name.replace(" ", "_"), sim)
            if rt is None:
                continue
            t = time.monotonic()
            act(sim)
            said = rt.wait_line(needle, 5.0)
            check(said is not None and "FAULT" in said[1],
                  f"{name}: the device's FAULT names it: {said[1] if said else rt.text()[-400:]}")
            if name != "fault":  # the arm still takes commands: the device's zero wrench reaches it
                z = zero_after(sim, t, 2.0)
                check(z is not None and last_wrench_is_zero(sim), f"{name}: the last wrench on the arm is zero")
            else:  # in FAULT the arm takes nothing (and is powered off): nothing after the fault
                late = [c for c in sim.commands(WRENCH, since=t + 0.05) if nonzero(c.value)]
                check(not late, f"{name}: no wrench after the arm's FAULT ({len(late)})")
            if name == "error":
                said = rt.wait_line("simulated tracking error", 5.0)
                check(said is not None, f"{name}: the arm's words are in saw-rt's log: {said[1] if said else ''}")
            rc = rt.stop(signal.SIGTERM)
            check(rc == 0, f"{name}: saw-rt stopped in order (exit {rc})")
            if "stamps" in name:
                stats = [line for _, line in rt.lines if "badly stamped" in line]
                check(bool(stats) and " 0 badly stamped" not in stats[-1],
                      f"{name}: the gateway counted them: {stats[-1] if stats else '(no statistics)'}")


def main(saw_rt):
    tag = str(os.getpid())
    domain = dds_domain()
    work = tempfile.mkdtemp()
    handshake_and_follow(saw_rt, work, tag, domain)
    kill_paths(saw_rt, work, tag, domain)
    arm_faults(saw_rt, work, tag, domain)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
