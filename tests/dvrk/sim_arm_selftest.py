"""Self-test of the simulated dVRK arm (tests/dvrk/sim_arm.py): a CRTK client on another Cyclone DDS
participant (and, for the command line, in another process) drives a simulated PSM and MTM the way
the reference client (crtk_python_client) drives a real dVRK, with its own QoS, and checks that the
arm behaves as docs/design/dvrk-arms.md Part A says a dVRK 2.4 arm does:

(a) before ENABLED+homed a motion command changes nothing and earns a throttled warning (A2);
(b) `home` is refused in DISABLED (warning, no state change), `enable` goes DISABLED+busy then
    ENABLED, `home` in ENABLED goes busy then homed, and the arm is at home (A2);
(c) servo_cp moves a PSM to the goal and it stays there after the commands stop (A3: no timeout);
    move_cp is busy then goal_reached; the cannula flag refuses Cartesian commands (A2);
(d) body/servo_cf moves an MTM and the last wrench keeps acting after the commands stop (A3);
    without gravity compensation a free MTM sinks (A5);
(e) a best-effort writer's servo_cp never reaches the arm: it does not match (A4);
(f) a late transient-local reader gets the current operating_state at once (A4);
(g) console/clutch carries [1] pressed, [0] released and [2] for a quick tap (A1);
and: unknown and refused state commands give warnings, a scripted fault is FAULT with an error
text and `enable` leaves it, the arm is quiet at idle, stop() leaves the domain, and the command
line runs an arm in its own process that exits cleanly on SIGTERM.

Every check is printed (`ok   ...` / `FAIL ...`); the exit code is 1 if any failed. Waits are polls
with a bound, never a sleep that hopes.

usage: sim_arm_selftest.py
"""
import math
import os
import queue
import signal
import subprocess
import sys
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "..", "interop"))
import sim_arm as S  # noqa: E402  (first: it sets CYCLONEDDS_URI before cyclonedds is loaded)
from harness import check, dds_domain, exit_code  # noqa: E402

from cyclonedds.core import Policy, Qos  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.idl import IdlStruct  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402

# The client's own QoS, as the reference client and our gateway would ask (A4), not the sim's.
_REL = Policy.Reliability.Reliable(max_blocking_time=duration(milliseconds=100))
WRITER = Qos(_REL, Policy.Durability.Volatile, Policy.History.KeepLast(10), S.XCDR1)
LATCHED_WRITER = Qos(_REL, Policy.Durability.TransientLocal, Policy.History.KeepLast(10), S.XCDR1)
BEST_EFFORT_WRITER = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(10), S.XCDR1)
EVENT_READER = Qos(_REL, Policy.Durability.TransientLocal, Policy.History.KeepLast(100), S.XCDR1)
STATE_READER = Qos(Policy.Reliability.BestEffort, Policy.History.KeepLast(100), S.XCDR1)

TOL = 5e-4  # m: "at the goal"


class Stream:
    """The samples of one reader in arrival order, each with its local arrival time."""

    def __init__(self, reader):
        self.reader = reader
        self.samples, self.times = [], []

    def poll(self):
        for s in self.reader.take(N=256):
            if isinstance(s, IdlStruct):  # skips a writer's unregistration (InvalidSample)
                self.samples.append(s)
                self.times.append(time.monotonic())
        return len(self.samples)

    def mark(self):
        return self.poll()

    def wait(self, pred, timeout=2.0, start=0):
        """The first sample from index `start` for which pred holds, or None after `timeout` s."""
        deadline = time.monotonic() + timeout
        while True:
            self.poll()
            for s in self.samples[start:]:
                if pred(s):
                    return s
            if time.monotonic() >= deadline:
                return None
            time.sleep(0.005)

    def next(self, n, timeout=2.0):
        """The next `n` samples from now on (fewer if the stream stops)."""
        start = self.mark()
        deadline = time.monotonic() + timeout
        while self.poll() < start + n and time.monotonic() < deadline:
            time.sleep(0.005)
        return self.samples[start:start + n], self.times[start:start + n]

    def last(self, timeout=2.0):
        if self.poll() == 0:
            self.wait(lambda s: True, timeout)
        return self.samples[-1] if self.samples else None


class Client:
    """A CRTK client on its own participant: writers wait until they match before the first write
    (a reliable volatile sample written before matching is lost, not late)."""

    def __init__(self, domain):
        self.dp = DomainParticipant(domain)
        self.topics = {}

    def topic(self, name, kind):
        if name not in self.topics:
            self.topics[name] = Topic(self.dp, name, kind)
        return self.topics[name]

    def writer(self, name, kind, qos=WRITER, matched=True):
        w = DataWriter(self.dp, self.topic(name, kind), qos=qos)
        if matched and not poll_until(lambda: w.get_publication_matched_status().current_count > 0, 3.0):
            raise RuntimeError(f"no subscription matched on {name}")
        return w

    def stream(self, name, kind, qos=EVENT_READER):
        return Stream(DataReader(self.dp, self.topic(name, kind), qos=qos))


def poll_until(cond, timeout, every=0.005):
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() >= deadline:
            return False
        time.sleep(every)
    return True


def pos(sample):
    p = sample.pose.position
    return (p.x, p.y, p.z)


def quat(sample):
    o = sample.pose.orientation
    return (o.x, o.y, o.z, o.w)


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def pose_msg(p, q=(0.0, 0.0, 0.0, 1.0)):
    return S.PoseStamped(header=S.Header(stamp=S.stamp_of(time.time())),
                         pose=S.Pose(position=S.Point(*p), orientation=S.Quaternion(*q)))


def state_is(state, homed=None, busy=None):
    return lambda s: (s.state == state and (homed is None or s.is_homed == homed)
                      and (busy is None or s.is_busy == busy))


class ArmClient:
    """The client's view of one arm: state_command, the operating_state/warning/error events."""

    def __init__(self, client, arm):
        self.client, self.arm = client, arm
        self.state = client.stream(f"rt/{arm}/operating_state", S.OperatingState)
        self.warning = client.stream(f"rt/{arm}/warning", S.String)
        self.error = client.stream(f"rt/{arm}/error", S.String)
        self.cp = client.stream(f"rt/{arm}/measured_cp", S.PoseStamped, STATE_READER)
        # The reference client latches state_command (A4); the arm's volatile reader ignores that.
        self.command = client.writer(f"rt/{arm}/state_command", S.StringStamped, LATCHED_WRITER)

    def send(self, text):
        self.command.write(S.StringStamped(header=S.Header(stamp=S.stamp_of(time.time())), string=text))

    def enable_and_home(self):
        """crtk_python_client's way: enable, wait for ENABLED, then home, wait for homed and not busy."""
        start = self.state.mark()
        self.send("enable")
        if self.state.wait(state_is("ENABLED", busy=False), 3.0, start) is None:
            return False
        start = self.state.mark()
        self.send("home")
        return self.state.wait(state_is("ENABLED", homed=True, busy=False), 3.0, start) is not None


def warned(arm_client, start, *words, timeout=1.0):
    return arm_client.warning.wait(lambda s: all(w in s.data for w in words), timeout, start)


def check_not_ready(psm, c, home_p):
    """(a)"""
    p0 = pos(c.cp.last())
    servo = c.client.writer("rt/PSM1/servo_cp", S.PoseStamped)
    w0 = c.warning.mark()
    since = time.monotonic()
    servo.write(pose_msg((p0[0] + 0.03, p0[1], p0[2])))
    arrived = psm.wait_command("servo_cp", since=since)
    check(arrived is not None, "(a) a reliable servo_cp written before ENABLED+homed reaches the arm")
    check(warned(c, w0, "servo_cp", "arm not ready") is not None,
          "(a) ... and is dropped with the warning 'PSM1: servo_cp, arm not ready'")
    samples, _ = c.cp.next(10)
    check(len(samples) == 10 and all(dist(pos(s), p0) < 1e-9 for s in samples),
          "(a) ... and measured_cp stays where it was over the next 10 samples")
    w1 = c.warning.mark()
    since = time.monotonic()
    for _ in range(3):
        servo.write(pose_msg((p0[0] + 0.03, p0[1], p0[2])))
    # The arm warns while it takes the command, so once it is recorded a warning would be out.
    check(psm.wait_command("servo_cp", since=since) is not None
          and c.warning.wait(lambda s: "arm not ready" in s.data, 0.1, w1) is None,
          "(a) further refused motion commands within 2 s send no more warnings (throttled)")
    return servo


def check_handshake(psm, c, home_p):
    """(b)"""
    w0, s0 = c.warning.mark(), c.state.mark()
    c.send("home")
    check(warned(c, w0, "home", "not allowed", "DISABLED") is not None,
          "(b) home in DISABLED is refused with a warning")
    check(psm.operating_state() == ("DISABLED", False, False) and c.state.wait(lambda s: True, 0.05, s0) is None,
          "(b) ... and the state does not change (no operating_state published)")
    w0 = c.warning.mark()
    c.send("bogus")
    check(warned(c, w0, "bogus", "valid state_command") is not None and psm.operating_state()[0] == "DISABLED",
          "(b) an unknown state_command only earns a warning")
    s0 = c.state.mark()
    t_sent = time.monotonic()
    c.send("enable")
    busy = c.state.wait(state_is("DISABLED", homed=False, busy=True), 1.0, s0)
    check(busy is not None, "(b) enable: DISABLED + is_busy while powering")
    enabled = c.state.wait(state_is("ENABLED", busy=False), 2.0, s0)
    t_enabled = time.monotonic()
    check(enabled is not None and not enabled.is_homed, "(b) ... then ENABLED, not homed")
    check(t_enabled - t_sent >= psm.p.power_time, f"(b) ... after the power time ({t_enabled - t_sent:.3f} s"
          f" >= {psm.p.power_time} s)")
    s0 = c.state.mark()
    c.send("home")
    check(c.state.wait(state_is("ENABLED", homed=False, busy=True), 1.0, s0) is not None,
          "(b) home in ENABLED: ENABLED + is_busy while the homing trajectory runs")
    check(c.state.wait(state_is("ENABLED", homed=True, busy=False), 2.0, s0) is not None,
          "(b) ... then ENABLED, is_homed, not busy")
    check(c.cp.wait(lambda s: dist(pos(s), home_p) < TOL, 1.0) is not None, "(b) ... and the arm is at its home pose")


def check_servo_and_hold_forever(psm, c, servo, home_p):
    """(c)"""
    goal = (home_p[0] + 0.03, home_p[1] - 0.02, home_p[2] + 0.01)
    q_goal = (0.0, 0.0, math.sin(0.15), math.cos(0.15))  # 0.3 rad about z
    servo.write(pose_msg(goal, q_goal))
    reached = c.cp.wait(lambda s: dist(pos(s), goal) < TOL and S.qangle(quat(s), q_goal) < 0.01, 2.0, c.cp.mark())
    check(reached is not None, "(c) one servo_cp: the PSM moves to the goal (position and orientation)")
    last = psm.commands("servo_cp")[-1].time
    samples, times = c.cp.next(40, 2.0)
    check(len(samples) == 40 and times[-1] - last > 0.3 and all(dist(pos(s), goal) < TOL for s in samples),
          f"(c) ... and stays there with no new command ({times[-1] - last if times else 0:.2f} s after the last one)")

    sp = c.client.stream("rt/PSM1/setpoint_cp", S.PoseStamped, STATE_READER)
    check(sp.wait(lambda s: dist(pos(s), goal) < TOL, 1.0) is not None, "(c) setpoint_cp is at the goal too")

    move = c.client.writer("rt/PSM1/move_cp", S.PoseStamped)
    goal_reached = c.client.stream("rt/PSM1/goal_reached", S.Bool)
    s0 = c.state.mark()
    move.write(pose_msg(home_p))
    check(c.state.wait(state_is("ENABLED", homed=True, busy=True), 1.0, s0) is not None,
          "(c) move_cp: is_busy while the trajectory runs")
    check(goal_reached.wait(lambda s: s.data, 3.0) is not None
          and c.state.wait(state_is("ENABLED", homed=True, busy=False), 1.0, s0) is not None
          and dist(psm.position(), home_p) < TOL,
          "(c) ... then goal_reached true, not busy, at the goal")

    psm.set_cannula_ready(False)
    w0 = c.warning.mark()
    since = time.monotonic()
    servo.write(pose_msg(goal))
    psm.wait_command("servo_cp", since=since)
    check(warned(c, w0, "inserted past the cannula") is not None,
          "(c) tool not past the cannula: servo_cp refused with the dVRK's warning")
    samples, _ = c.cp.next(10)
    check(len(samples) == 10 and all(dist(pos(s), home_p) < TOL for s in samples), "(c) ... and the PSM does not move")
    psm.set_cannula_ready(True)


def check_mtm_wrench_forever(mtm, client):
    """(d)"""
    c = ArmClient(client, "MTML")
    check(c.enable_and_home(), "(d) MTML: enable, wait ENABLED, home, wait homed (the reference client's handshake)")
    gc = client.writer("rt/MTML/use_gravity_compensation", S.Bool)
    cf = client.writer("rt/MTML/body/servo_cf", S.WrenchStamped)
    cv = client.stream("rt/MTML/measured_cv", S.TwistStamped, STATE_READER)
    measured_cf = client.stream("rt/MTML/body/measured_cf", S.WrenchStamped, STATE_READER)
    since = time.monotonic()
    gc.write(S.Bool(data=True))
    check(mtm.wait_command("use_gravity_compensation", lambda v: v.data, since=since) is not None,
          "(d) use_gravity_compensation true reaches the MTM")
    x0 = pos(c.cp.last())[0]
    force = 0.5
    cf.write(S.WrenchStamped(wrench=S.Wrench(force=S.Vector3(x=force))))
    check(c.cp.wait(lambda s: pos(s)[0] > x0 + 0.01, 2.0, c.cp.mark()) is not None,
          "(d) one body/servo_cf of 0.5 N along x: the MTM moves along x")
    check(measured_cf.wait(lambda s: abs(s.wrench.force.x - force) < 1e-9, 1.0) is not None,
          "(d) body/measured_cf reports the wrench applied")
    last = mtm.commands("body/servo_cf")[-1].time
    terminal = force / mtm.p.damping
    samples, times = cv.next(40, 2.0)
    late = [s for s, t in zip(samples, times) if t - last > 0.3]
    check(len(late) > 5 and all(s.twist.linear.x > 0.8 * terminal for s in late),
          f"(d) ... and the last wrench keeps pushing with no new command (x velocity ~{terminal} m/s"
          f" {times[-1] - last if times else 0:.2f} s after it)")
    cf.write(S.WrenchStamped())
    check(cv.wait(lambda s: abs(s.twist.linear.x) < 0.002, 2.0, cv.mark()) is not None,
          "(d) a zero wrench replaces it: the MTM comes to rest")
    free = client.writer("rt/MTML/free", S.Empty)
    since = time.monotonic()
    gc.write(S.Bool(data=False))
    free.write(S.Empty())
    mtm.wait_command("free", since=since)
    z0 = pos(c.cp.last())[2]
    check(c.cp.wait(lambda s: pos(s)[2] < z0 - 0.01, 2.0, c.cp.mark()) is not None,
          "(d) free without gravity compensation: the MTM sinks")
    return c


def check_best_effort_not_matched(psm, client, home_p):
    """(e)"""
    be = client.writer("rt/PSM1/servo_cp", S.PoseStamped, BEST_EFFORT_WRITER, matched=False)
    check(poll_until(lambda: be.get_offered_incompatible_qos_status().total_count > 0, 3.0),
          "(e) a best-effort servo_cp writer meets the arm's reliable reader as incompatible QoS")
    check(be.get_publication_matched_status().current_count == 0, "(e) ... and matches nothing")
    far = (home_p[0] + 0.25, home_p[1], home_p[2])
    for _ in range(5):
        be.write(pose_msg(far))
    since = time.monotonic()
    hold = client.writer("rt/PSM1/hold", S.Empty)
    hold.write(S.Empty())  # a reliable marker written after the best-effort samples
    check(psm.wait_command("hold", since=since) is not None
          and not any(abs(c.value.pose.position.x - far[0]) < 1e-9 for c in psm.commands("servo_cp"))
          and dist(psm.position(), home_p) < TOL,
          "(e) ... its samples never reach the arm (a reliable marker after them does)")


def check_late_joiner(client):
    """(f)"""
    late = client.stream("rt/PSM1/operating_state", S.OperatingState, EVENT_READER)
    t0 = time.monotonic()
    got = late.wait(lambda s: True, 1.0)
    late.poll()
    last = late.samples[-1] if late.samples else None
    check(got is not None and state_is("ENABLED", homed=True, busy=False)(last),
          f"(f) a transient-local reader joining late gets the current operating_state at once "
          f"({time.monotonic() - t0:.3f} s): {last.state if last else None}, homed {last.is_homed if last else None}")
    volatile = client.stream("rt/PSM1/operating_state", S.OperatingState,
                             Qos(_REL, Policy.Durability.Volatile, Policy.History.KeepLast(10), S.XCDR1))
    check(volatile.wait(lambda s: True, 0.3) is None, "(f) (a volatile late reader gets nothing until the next change)")


def check_console(mtm, client):
    """(g)"""
    clutch = client.stream("rt/console/clutch", S.Joy)
    check(poll_until(lambda: clutch.reader.get_subscription_matched_status().current_count > 0, 3.0),
          "(g) console/clutch is published by the MTM-side console")
    start = clutch.mark()
    mtm.press("clutch")
    mtm.release("clutch")
    mtm.tap("clutch")
    poll_until(lambda: clutch.poll() >= start + 3, 2.0)
    got = [list(s.buttons) for s in clutch.samples[start:]]
    check(got == [[1], [0], [2]], f"(g) press, release, quick tap: buttons {got} (expected [[1], [0], [2]])")


def check_fault(psm, client):
    c = ArmClient(client, "PSM1")
    s0, e0 = c.state.mark(), c.error.mark()
    psm.fault("encoder error")
    check(c.state.wait(state_is("FAULT", busy=False), 1.0, s0) is not None
          and c.error.wait(lambda s: "encoder error" in s.data, 1.0, e0) is not None,
          "a scripted fault: FAULT on operating_state and the reason on ARM/error")
    s0 = c.state.mark()
    c.send("enable")
    check(c.state.wait(state_is("ENABLED", busy=False), 2.0, s0) is not None, "enable is taken in FAULT (ValidCommand)")
    s0, w0 = c.state.mark(), c.warning.mark()
    c.send("resume")
    check(warned(c, w0, "resume", "not allowed") is not None, "resume in ENABLED is refused with a warning")
    c.send("pause")
    check(c.state.wait(state_is("PAUSED"), 1.0, s0) is not None, "pause in ENABLED: PAUSED")
    c.send("disable")
    check(c.state.wait(state_is("DISABLED", busy=False), 1.0, s0) is not None, "disable in PAUSED: DISABLED at once")


def check_quiet_at_idle():
    cpu0, t0 = time.process_time(), time.monotonic()
    time.sleep(0.5)  # measuring idle CPU: nothing to wait for
    share = (time.process_time() - cpu0) / (time.monotonic() - t0)
    check(share < 0.5, f"two idle arms publishing at 100 Hz use {100 * share:.0f}% of a core (< 50%)")


def check_stop_leaves(sim, writer):
    sim.stop()
    check(poll_until(lambda: writer.get_publication_matched_status().current_count == 0, 3.0),
          f"stop(): {sim.arm}'s readers leave the domain")


def check_command_line(domain, client):
    """The arm as its own process, across the loopback: latched state, a command, SIGTERM."""
    proc = subprocess.Popen([sys.executable, os.path.join(HERE, "sim_arm.py"), "--arm", "PSM3", "--domain",
                             str(domain), "--echo", "--power-time", "0.05"],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    lines = queue.Queue()
    threading.Thread(target=lambda: [lines.put(l) for l in proc.stdout], daemon=True).start()

    def line_with(text, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                line = lines.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                return None
            if text in line:
                return line
        return None

    try:
        check(line_with("ready PSM3 psm", 15.0) is not None, "command line: sim_arm.py --arm PSM3 starts and says ready")
        c = ArmClient(client, "PSM3")
        check(c.state.wait(state_is("DISABLED", busy=False), 3.0) is not None,
              "command line: its latched operating_state (DISABLED) reaches this process")
        c.send("enable")
        check(line_with("state_command enable", 3.0) is not None
              and c.state.wait(state_is("ENABLED"), 3.0) is not None,
              "command line: --echo prints the command received, and the arm enables")
        proc.send_signal(signal.SIGTERM)
        try:
            rc = proc.wait(timeout=5.0)
        except subprocess.TimeoutExpired:
            rc = None
        check(rc == 0, f"command line: SIGTERM ends it cleanly (exit code {rc})")
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def main():
    t_start = time.monotonic()
    domain = dds_domain()
    print(f"domain {domain}", flush=True)
    psm = S.SimArm("PSM1", domain, kind="psm")
    mtm = S.SimArm("MTML", domain, kind="mtm")
    home_p = psm.home_p
    with psm, mtm:
        client = Client(domain)
        c = ArmClient(client, "PSM1")
        check(c.state.wait(state_is("DISABLED", homed=False, busy=False), 3.0) is not None,
              "a reader joining after the start gets DISABLED, not homed (the startup state)")
        servo = check_not_ready(psm, c, home_p)
        check_handshake(psm, c, home_p)
        check_servo_and_hold_forever(psm, c, servo, home_p)
        check_best_effort_not_matched(psm, client, home_p)
        check_late_joiner(client)
        m = check_mtm_wrench_forever(mtm, client)
        check_console(mtm, client)
        check_fault(psm, client)
        check_quiet_at_idle()
        check_stop_leaves(psm, servo)
        check_stop_leaves(mtm, m.command)
    check_command_line(domain, client)
    print(f"{time.monotonic() - t_start:.1f} s", flush=True)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main())
