"""A simulated dVRK 2.4 arm (MTM, PSM or ECM) speaking ROS 2's DDS through Cyclone DDS, for the tests of
our own dVRK driver: it stands where a real `dvrk_system` arm would be.

Written independently of sawrt's code. The facts come from docs/design/dvrk-arms.md Part A (which
cites the upstream sawIntuitiveResearchKit 2.4, cisst-ros and cisst sources) and C7 (this simulator's
specification), and from the ROS message definitions; the message types below are this file's own
Cyclone DDS dataclasses, not sawdds.msgs, so that a mistake shared with the repository's IDL cannot
pass unnoticed:

* A1  topics `rt/<ARM>/<command>`, types `pkg::msg::dds_::Type_`, XCDR1; console buttons Joy
      [1] pressed, [0] released, [2] quick tap; errors and warnings are std_msgs/String.
* A2  the operating-state machine: DISABLED at start; `enable` is DISABLED+busy while powering,
      then ENABLED (not homed); `home` is taken in ENABLED only and is ENABLED+busy while the arm
      moves home; the ValidCommand table for enable/disable/home/unhome/pause/resume; an unknown
      or refused command only sends a warning; motion commands need ArmIsReady, else they are
      dropped with a warning throttled to one per 2 s; a PSM refuses Cartesian commands until its
      tool is past the cannula.
* A3  no command timeout: a PSM holds its last servo goal and an MTM applies its last body wrench
      for ever (the wrench is re-applied every control step from the stored value).
* A4  QoS: command subscriptions RELIABLE, VOLATILE, KEEP_LAST 1; state publishers RELIABLE,
      KEEP_LAST 100; event publishers (operating_state, warning, error, goal_reached, console
      buttons) RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 100. A best-effort writer matches no command.
* A5  hold (goal := current setpoint) and free (no effort) as std_msgs/Empty topics.

The kinematics is a Cartesian gantry (joints x, y, z and the orientation's rotation vector): the
protocol and the behaviour over time are the subject, not the dVRK's real joints.

As a command: `sim_arm.py --arm PSM1 --domain N [--kind psm|mtm] [--rate 100] ...` runs one arm
until SIGINT/SIGTERM or a `quit` line, prints `ready` once its entities exist, and takes one action
a line on its standard input (`fault WHY`, `tap clutch`, `press camera`, `pause-publishing`, ...;
`help` lists them). `--echo` prints every command received (`cmd <monotonic time> <topic> <value>`).
"""
import argparse
import math
import os
import signal
import sys
import threading
import time
from collections import namedtuple
from dataclasses import dataclass, field

# Loopback DDS and the ROS 2 messages and QoS (ros_msgs.py sets CYCLONEDDS_URI before cyclonedds loads).
from ros_msgs import *  # noqa: E402,F401,F403  (the message types, re-exported for the tests)
from ros_msgs import COMMAND_QOS, EVENT_QOS, STATE_QOS, stamp_of  # noqa: E402
from geometry import (add, finite, from_rotvec, norm, qangle, qconj, qmul, qnormalize, rotate,  # noqa: E402,F401
                      scale, slerp, sub, to_rotvec)
from cyclonedds.core import GuardCondition, InstanceState, Policy, Qos, ReadCondition, SampleState, ViewState  # noqa: E402
from cyclonedds.core import WaitSet  # noqa: E402
from cyclonedds.domain import DomainParticipant  # noqa: E402
from cyclonedds.pub import DataWriter  # noqa: E402
from cyclonedds.sub import DataReader  # noqa: E402
from cyclonedds.topic import Topic  # noqa: E402
from cyclonedds.util import duration  # noqa: E402


# What each arm subscribes to (A1): command name -> type. `body/servo_cf` is the dVRK's only
# Cartesian force command (there is no plain servo_cf).
COMMANDS_ALL = {
    "state_command": StringStamped,
    "servo_cp": PoseStamped,
    "move_cp": PoseStamped,
    "servo_jp": JointState,
    "move_jp": JointState,
    "body/servo_cf": WrenchStamped,
    "body/set_cf_orientation_absolute": Bool,
    "use_gravity_compensation": Bool,
    "hold": Empty,
    "free": Empty,
}
COMMANDS_PSM = {"jaw/servo_jp": JointState}
CONSOLE_BUTTONS = ("clutch", "operator_present", "camera")
RELEASED, PRESSED, CLICKED = 0, 1, 2  # Joy.buttons values (A1)

# prmOperatingState's ValidCommand (A2): which state_command each CRTK state accepts.
VALID_COMMANDS = {
    "DISABLED": {"enable", "disable", "unhome"},
    "ENABLED": {"enable", "disable", "pause", "home", "unhome"},
    "PAUSED": {"disable", "pause", "resume", "unhome"},
    "FAULT": {"enable", "disable", "unhome"},
}
STATE_COMMANDS = {"enable", "disable", "home", "unhome", "pause", "resume"}
JOINT_NAMES = ("x", "y", "z", "rx", "ry", "rz")

Command = namedtuple("Command", "time topic value")  # time: time.monotonic() at arrival


# --- motion ---

class Trajectory:
    """A smooth (cubic) move of the setpoint from one pose to another over a fixed time, as the
    dVRK's move_* and homing do (A2): the arm is busy until it ends."""

    def __init__(self, t0, p0, q0, p1, q1, length, homing=False):
        self.t0, self.p0, self.q0, self.p1, self.q1 = t0, p0, q0, p1, q1
        self.length = max(length, 1e-3)
        self.homing = homing

    def at(self, now):
        u = min(1.0, max(0.0, (now - self.t0) / self.length))
        s = u * u * (3.0 - 2.0 * u)
        return add(self.p0, scale(sub(self.p1, self.p0), s)), slerp(self.q0, self.q1, s)

    def done(self, now):
        return now - self.t0 >= self.length


@dataclass
class Params:
    """What a test may change; the defaults give a quick handshake (seconds, metres, kilograms)."""
    power_time: float = 0.2          # DISABLED+busy after `enable`
    home_time: float = 0.5           # ENABLED+busy while the homing trajectory runs
    step_rate: float = 1500.0        # control steps per second (the dVRK's arm rate, A1 "Rates")
    max_speed: float = 0.2           # setpoint rate limit, m/s
    max_angular_speed: float = 3.0   # rad/s
    track_time: float = 0.02         # first-order time constant of the setpoint toward the goal
    lag_time: float = 0.005          # measured behind setpoint (PSM)
    move_speed: float = 0.1          # move_cp/move_jp average speed, m/s
    jaw_speed: float = 2.0           # rad/s
    mass: float = 0.5                # MTM point mass
    damping: float = 5.0             # MTM viscous damping, N s/m
    kp: float = 2000.0               # MTM position PID, N/m
    kd: float = 60.0                 # N s/m
    gravity: float = 9.81
    workspace: float = 0.4           # the MTM stays within +/- this of home on each axis
    hand_stiffness: float = 200.0    # scripted hand, N/m
    # Motion commands also refused while is_busy (a move_* running), as our tests' contract asks.
    # Upstream ArmIsReady (A2) tests only ENABLED and homed, so a dVRK lets servo_*/hold preempt a
    # move: False behaves that way.
    refuse_when_busy: bool = True


class SimArm:
    """One simulated dVRK arm on its own DomainParticipant. start()/stop() or `with SimArm(...)`.

    All state lives behind one lock; a single thread takes commands (woken by a WaitSet), steps the
    dynamics by wall time in fixed 1/step_rate steps, and publishes at `rate` Hz."""

    def __init__(self, arm, domain, kind=None, rate=100.0, namespace="", console=None, params=None,
                 home=None, start=None, hand=None, echo=None, home_q=None):
        self.arm = arm
        self.kind = kind or ("mtm" if arm.upper().startswith("MTM") else "ecm" if arm.upper() == "ECM" else "psm")
        if self.kind not in ("mtm", "psm", "ecm"):
            raise ValueError(f"kind must be mtm, psm or ecm, not {self.kind!r}")
        # A PSM and an ECM follow position goals alike (an ECM is a PSM without a jaw here: its
        # measured_cp orientation is the camera's).
        self.follows = self.kind in ("psm", "ecm")
        self.domain = domain
        self.rate = float(rate)
        self.p = params or Params()
        self.prefix = "rt/" + (namespace.strip("/") + "/" if namespace.strip("/") else "")
        self.console = (self.kind == "mtm") if console is None else console
        self.echo = echo  # callable(Command) for each command received, or None
        self._lock = threading.RLock()
        self._thread = None
        self._running = False
        self._dp = None

        # Operating state (A2). _powering_until / the homing trajectory carry the busy phases.
        self._state, self._homed, self._busy = "DISABLED", False, False
        self._powering_until = None
        self._published_state = None
        # Motion.
        self.home_p = tuple(home) if home is not None else ((0.0, 0.0, -0.1) if self.follows else (0.0, 0.0, 0.0))
        self.home_q = qnormalize(tuple(home_q)) if home_q is not None else (0.0, 0.0, 0.0, 1.0)
        start_p = tuple(start) if start is not None else add(self.home_p, (0.01, -0.01, 0.02))
        self._meas_p, self._meas_q = start_p, self.home_q
        self._sp_p, self._sp_q = start_p, self.home_q
        self._v, self._w = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        self._mode = "idle"             # idle (PID off) | position | trajectory | effort | free
        self._goal_p, self._goal_q = start_p, self.home_q
        self._traj = None
        self._wrench = (0.0, 0.0, 0.0)  # stored body/servo_cf force, applied every step (A3)
        self._applied = (0.0, 0.0, 0.0)  # the arm's own force last step (base frame)
        self._cf_absolute = False
        self._gravity_compensation = False
        self._jaw_sp = self._jaw_meas = self._jaw_goal = 0.5
        self._gripper = 0.5
        self._hand = hand               # (amplitude m, frequency Hz[, axis[, twist rad]]) or None
        self._t_sim = None
        self._t0 = None
        # Options for the stream tests (C5, C7).
        self._publishing = True
        self._invalid_stamps = False
        self._frozen_stamp = None
        self.cannula_ready = True
        # Records.
        self._commands = []
        self._warnings = []
        self._errors = []
        self._throttle = {}  # key -> [time of last message, count since]

    # --- lifecycle ---

    def start(self):
        self._dp = DomainParticipant(self.domain)
        self._make_entities()
        self._t0 = self._t_sim = time.monotonic()
        with self._lock:
            self._publish_operating_state(force=True)
        self._running = True
        self._thread = threading.Thread(target=self._run, name=f"sim-{self.arm}", daemon=True)
        self._thread.start()
        return self

    def stop(self):
        if self._thread is None:
            return
        self._running = False
        self._wake.set(True)
        self._thread.join(timeout=5.0)
        self._thread = None
        # Dropping the participant deletes every entity under it (and tells the peers at once).
        self._waitset = self._wake = None
        self._readers, self._writers, self._topics = {}, {}, {}
        self._dp = None

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    # --- test accessors (thread-safe) ---

    def commands(self, topic=None, since=0.0):
        """Every command received: [Command(time, topic, value)], oldest first (time.monotonic())."""
        with self._lock:
            return [c for c in self._commands if (topic is None or c.topic == topic) and c.time >= since]

    def wait_command(self, topic, pred=None, timeout=2.0, since=0.0):
        """The first command on `topic` received at or after `since` for which pred(value) holds,
        or None after `timeout` s."""
        deadline = time.monotonic() + timeout
        while True:
            for c in self.commands(topic, since):
                if pred is None or pred(c.value):
                    return c
            if time.monotonic() >= deadline:
                return None
            time.sleep(0.002)

    def warnings(self):
        with self._lock:
            return list(self._warnings)

    def errors(self):
        with self._lock:
            return list(self._errors)

    def operating_state(self):
        """(state, is_homed, is_busy) as the arm publishes it."""
        with self._lock:
            return self._crtk_state()

    def position(self):
        with self._lock:
            return self._meas_p

    def setpoint(self):
        with self._lock:
            return self._sp_p

    def velocity(self):
        with self._lock:
            return self._v

    def stored_wrench(self):
        with self._lock:
            return self._wrench

    # --- scripted events ---

    def fault(self, why="simulated fault"):
        """FAULT now (EnterFault: power off), with `why` on ARM/error."""
        with self._lock:
            self._cancel_motion()
            self._powering_until = None
            self._state, self._homed, self._busy = "FAULT", False, False
            self._mode = "idle"
            self._send_error(f"{self.arm}: {why}")
            self._publish_operating_state()

    def powered_and_homed(self):
        """ENABLED and homed, holding where it is, gravity compensated: an MTM as the dVRK's console
        and its teleoperation leave it (saw-rt sends an MTM no state_command here, nor
        use_gravity_compensation)."""
        with self._lock:
            self._cancel_motion()
            self._powering_until = None
            self._state, self._homed, self._busy = "ENABLED", True, False
            self._gravity_compensation = True
            self._hold_here()
            self._publish_operating_state()

    def report_error(self, text):
        """An error message on ARM/error without a state change (as the dVRK reports, e.g., a
        tracking error it recovers from)."""
        with self._lock:
            self._send_error(f"{self.arm}: {text}")

    def press(self, button):
        self._button(button, PRESSED)

    def release(self, button):
        self._button(button, RELEASED)

    def tap(self, button):
        """A quick tap as the dVRK console reports it: one Joy with buttons [2] (CLICKED)."""
        self._button(button, CLICKED)

    def pause_publishing(self):
        with self._lock:
            self._publishing = False

    def resume_publishing(self):
        with self._lock:
            self._publishing = True

    def set_invalid_stamps(self, on=True):
        """Stamp 0 on the state topics: the dVRK's way of sending an invalid sample (A1 Headers)."""
        with self._lock:
            self._invalid_stamps = bool(on)

    def freeze_stamps(self, on=True):
        """Repeat one stamp on every state sample from now on (a frozen source)."""
        with self._lock:
            self._frozen_stamp = stamp_of(time.time()) if on else None

    def set_cannula_ready(self, ready):
        with self._lock:
            self.cannula_ready = bool(ready)

    def set_hand(self, hand):
        """The scripted hand on an MTM: (amplitude m, frequency Hz[, axis[, twist rad]]) or None."""
        with self._lock:
            self._hand = hand

    # --- DDS ---

    def _topic(self, name, kind):
        if name not in self._topics:
            self._topics[name] = Topic(self._dp, self.prefix + name, kind)
        return self._topics[name]

    def _make_entities(self):
        self._topics, self._readers, self._writers = {}, {}, {}
        self._waitset = WaitSet(self._dp)
        self._wake = GuardCondition(self._dp)
        self._waitset.attach(self._wake)
        commands = dict(COMMANDS_ALL, **(COMMANDS_PSM if self.kind == "psm" else {}))
        mask = SampleState.Any | ViewState.Any | InstanceState.Any
        for name, kind in commands.items():
            reader = DataReader(self._dp, self._topic(f"{self.arm}/{name}", kind), qos=COMMAND_QOS)
            self._readers[name] = (reader, ReadCondition(reader, mask))
            self._waitset.attach(self._readers[name][1])
        state = {"measured_cp": PoseStamped, "setpoint_cp": PoseStamped, "measured_cv": TwistStamped,
                 "measured_js": JointState, "setpoint_js": JointState}
        if self.kind == "mtm":
            state.update({"body/measured_cf": WrenchStamped, "gripper/measured_js": JointState})
        elif self.kind == "psm":
            state.update({"jaw/measured_js": JointState, "jaw/setpoint_js": JointState})
        for name, kind in state.items():
            self._writers[name] = DataWriter(self._dp, self._topic(f"{self.arm}/{name}", kind), qos=STATE_QOS)
        self._state_topics = tuple(state)
        events = {"operating_state": OperatingState, "warning": String, "error": String, "goal_reached": Bool}
        for name, kind in events.items():
            self._writers[name] = DataWriter(self._dp, self._topic(f"{self.arm}/{name}", kind), qos=EVENT_QOS)
        if self.console:
            for b in CONSOLE_BUTTONS:
                self._writers["console/" + b] = DataWriter(self._dp, self._topic(f"console/{b}", Joy), qos=EVENT_QOS)

    def _run(self):
        period = 1.0 / self.rate
        next_publish = time.monotonic()
        while self._running:
            # Sleeps in the WaitSet: woken by a command or stop(), else at the next publication.
            self._waitset.wait(duration(seconds=max(0.0, next_publish - time.monotonic())))
            if not self._running:
                break
            with self._lock:
                now = time.monotonic()
                self._advance(now)
                self._take_commands()
                if now >= next_publish:
                    self._publish_streams()
                    # Behind by more than a period (a stalled machine): skip, don't burst.
                    next_publish = max(next_publish + period, now)

    def _take_commands(self):
        for name, (reader, _) in self._readers.items():
            for sample in reader.take(N=32):
                if not isinstance(sample, IdlStruct):
                    continue  # a writer's dispose/unregister (InvalidSample)
                c = Command(time.monotonic(), name, sample)
                self._commands.append(c)
                if self.echo:
                    self.echo(c)
                self._on_command(name, sample)

    # --- publishing ---

    def _header(self):
        if self._invalid_stamps:
            return Header(stamp=Time(0, 0))
        return Header(stamp=self._frozen_stamp or stamp_of(time.time()))

    def _publish_streams(self):
        if not self._publishing:
            return
        h = self._header()
        # Like the dVRK's read publishers (A1 "Rates", RB.h:98): nobody subscribed, nothing sent.
        w = {}
        for name in self._state_topics:
            writer = self._writers[name]
            w[name] = writer if writer.get_publication_matched_status().current_count else _Muted
        w["measured_cp"].write(PoseStamped(header=h, pose=_pose(self._meas_p, self._meas_q)))
        w["setpoint_cp"].write(PoseStamped(header=h, pose=_pose(*self._setpoint_pose())))
        w["measured_cv"].write(TwistStamped(header=h, twist=Twist(linear=Vector3(*self._v), angular=Vector3(*self._w))))
        w["measured_js"].write(JointState(header=h, name=list(JOINT_NAMES),
                                          position=list(self._meas_p + to_rotvec(self._meas_q)),
                                          velocity=list(self._v + self._w), effort=list(self._applied) + [0.0] * 3))
        sp_p, sp_q = self._setpoint_pose()
        w["setpoint_js"].write(JointState(header=h, name=list(JOINT_NAMES), position=list(sp_p + to_rotvec(sp_q))))
        if self.kind == "mtm":
            body = rotate(qconj(self._meas_q), self._applied)
            w["body/measured_cf"].write(WrenchStamped(header=h, wrench=Wrench(force=Vector3(*body))))
            w["gripper/measured_js"].write(JointState(header=h, name=["gripper"], position=[self._gripper]))
        elif self.kind == "psm":
            w["jaw/measured_js"].write(JointState(header=h, name=["jaw"], position=[self._jaw_meas]))
            w["jaw/setpoint_js"].write(JointState(header=h, name=["jaw"], position=[self._jaw_sp]))

    def _setpoint_pose(self):
        # An MTM in effort mode (or unpowered) has no position setpoint: it reports where it is.
        if self.kind == "mtm" and self._mode not in ("position", "trajectory"):
            return self._meas_p, self._meas_q
        return self._sp_p, self._sp_q

    def _crtk_state(self):
        return self._state, self._homed, self._busy

    def _publish_operating_state(self, force=False):
        s = self._crtk_state()
        if force or s != self._published_state:
            self._published_state = s
            self._writers["operating_state"].write(OperatingState(
                header=Header(stamp=stamp_of(time.time())), state=s[0], is_homed=s[1], is_busy=s[2]))

    def _send_warning(self, text):
        self._warnings.append(text)
        self._writers["warning"].write(String(data=text))

    def _send_error(self, text):
        self._errors.append(text)
        self._writers["error"].write(String(data=text))

    def _warn_throttled(self, key, text):
        """One message per key per 2 s, with the count of those swallowed (ArmIsReady, A2)."""
        now = time.monotonic()
        last = self._throttle.setdefault(key, [-1e9, 0])
        last[1] += 1
        if now - last[0] > 2.0:
            self._send_warning(text + (f" ({last[1]} errors)" if last[1] > 1 else ""))
            last[0], last[1] = now, 0

    def _button(self, button, value):
        if button not in CONSOLE_BUTTONS:
            raise ValueError(f"unknown console button {button!r} (one of {', '.join(CONSOLE_BUTTONS)})")
        with self._lock:
            if not self.console:
                raise RuntimeError(f"{self.arm} was made without the console topics (console=True)")
            self._writers["console/" + button].write(Joy(header=Header(stamp=stamp_of(time.time())), buttons=[value]))

    # --- the state machine (A2) ---

    def _on_state_command(self, text):
        if text not in STATE_COMMANDS:
            self._send_warning(f"{self.arm}: {text} doesn't seem to be a valid state_command")
            return
        if text not in VALID_COMMANDS[self._state]:
            self._send_warning(f"{self.arm}: {text} is not allowed in state {self._state}")
            return
        getattr(self, "_cmd_" + text)()
        self._publish_operating_state()

    def _cmd_enable(self):
        if self._state in ("DISABLED", "FAULT") and self._powering_until is None:
            self._state, self._busy = "DISABLED", True  # POWERING
            self._powering_until = time.monotonic() + self.p.power_time

    def _cmd_disable(self):
        self._cancel_motion()
        self._powering_until = None
        # Power off (EnterDisabled); the sim forgets the homing with the power.
        self._state, self._homed, self._busy = "DISABLED", False, False
        self._mode = "idle"

    def _cmd_home(self):
        if self._homed or (self._traj is not None and self._traj.homing):
            return  # HOMED already, or on its way: nothing new to do
        self._cancel_motion()
        length = self.p.home_time
        self._traj = Trajectory(self._t_sim, self._meas_p, self._meas_q, self.home_p, self.home_q, length, homing=True)
        self._sp_p, self._sp_q = self._meas_p, self._meas_q
        self._mode = "trajectory"
        self._busy = True

    def _cmd_unhome(self):
        self._cancel_motion()
        self._homed = False
        if self._state == "ENABLED":
            self._mode = "idle"

    def _cmd_pause(self):
        if self._state == "ENABLED":
            self._cancel_motion()
            self._hold_here()
            self._state = "PAUSED"

    def _cmd_resume(self):
        self._state = "ENABLED"
        if self._homed:
            self._hold_here()
        else:
            self._mode = "idle"

    def _cancel_motion(self):
        if self._traj is not None:
            self._traj = None
            self._busy = False
            if self._mode == "trajectory":
                self._hold_here()

    def _hold_here(self):
        p, q = self._setpoint_pose()
        self._sp_p, self._sp_q = p, q
        self._goal_p, self._goal_q = p, q
        self._mode = "position"

    def _timed_transitions(self, now):
        if self._powering_until is not None and now >= self._powering_until:
            self._powering_until = None
            self._state, self._busy = "ENABLED", False
            self._mode = "idle"  # EnterEnabled: powered, PID off, until homed
            self._publish_operating_state()

    # --- commands ---

    def _arm_is_ready(self, method, cartesian):
        ready = self._state == "ENABLED" and self._homed and not (self.p.refuse_when_busy and self._busy)
        if not ready:
            self._warn_throttled("not_ready", f"{self.arm}: {method}, arm not ready")
            return False
        if cartesian and self.follows and not self.cannula_ready:
            self._warn_throttled("cannula", f"{self.arm}: tool/endoscope needs to be inserted past the cannula")
            return False
        return True

    def _on_command(self, name, msg):
        if name == "state_command":
            self._on_state_command(msg.string)
        elif name == "use_gravity_compensation":
            self._gravity_compensation = bool(msg.data)
        elif name == "body/set_cf_orientation_absolute":
            self._cf_absolute = bool(msg.data)
        elif name in ("servo_cp", "move_cp"):
            self._on_cartesian(name, msg.pose)
        elif name in ("servo_jp", "move_jp"):
            self._on_joint(name, msg.position)
        elif name == "jaw/servo_jp":
            if self._arm_is_ready(name, cartesian=False) and self._finite_or_warn(name, *msg.position[:1]):
                self._jaw_goal = msg.position[0] if msg.position else self._jaw_goal
        elif name == "body/servo_cf":
            f = msg.wrench.force
            if self._arm_is_ready(name, cartesian=True) and self._finite_or_warn(name, f.x, f.y, f.z):
                self._cancel_motion()
                self._wrench = (f.x, f.y, f.z)  # kept and re-applied every step until replaced (A3)
                # The sim's PSM is position-only: a wrench is recorded and stored, not simulated.
                if self.kind == "mtm":
                    self._mode = "effort"
        elif name == "hold":
            if self._arm_is_ready(name, cartesian=False):
                self._cancel_motion()
                self._hold_here()
        elif name == "free":
            if self._arm_is_ready(name, cartesian=False):
                self._cancel_motion()
                self._wrench = (0.0, 0.0, 0.0)
                self._mode = "free"

    def _finite_or_warn(self, name, *values):
        # Not the dVRK's behaviour (undocumented there): the sim keeps its dynamics finite.
        if finite(*values):
            return True
        self._warn_throttled("nonfinite", f"{self.arm}: {name}, non-finite value ignored by the simulator")
        return False

    def _on_cartesian(self, name, pose):
        p = (pose.position.x, pose.position.y, pose.position.z)
        q = (pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w)
        if not self._arm_is_ready(name, cartesian=True) or not self._finite_or_warn(name, *p, *q):
            return
        self._go(name, p, qnormalize(q))

    def _on_joint(self, name, position):
        if not self._arm_is_ready(name, cartesian=False):
            return
        if len(position) < len(JOINT_NAMES):
            self._warn_throttled("size", f"{self.arm}: {name}, expects {len(JOINT_NAMES)} joint positions")
            return
        if not self._finite_or_warn(name, *position):
            return
        self._go(name, tuple(position[:3]), from_rotvec(tuple(position[3:6])))

    def _go(self, name, p, q):
        if name.startswith("servo"):
            self._cancel_motion()
            if self._mode != "position":
                self._hold_here()
            self._goal_p, self._goal_q = p, q  # stored: held for ever without new commands (A3)
            return
        self._cancel_motion()
        sp_p, sp_q = self._setpoint_pose()
        length = max(norm(sub(p, sp_p)) / self.p.move_speed, qangle(sp_q, q) / (self.p.move_speed * 10.0), 0.05)
        self._traj = Trajectory(self._t_sim, sp_p, sp_q, p, q, length)
        self._sp_p, self._sp_q = sp_p, sp_q
        self._mode = "trajectory"
        self._busy = True
        self._publish_operating_state()

    # --- dynamics ---

    def _advance(self, now):
        dt = 1.0 / self.p.step_rate
        if now - self._t_sim > 0.5:
            self._t_sim = now - 0.5  # after a long stall, don't replay it all
        while self._t_sim + dt <= now:
            self._t_sim += dt
            self._step(dt, self._t_sim)
        self._timed_transitions(now)

    def _step(self, dt, now):
        if self._traj is not None:
            self._sp_p, self._sp_q = self._traj.at(now)
            if self._traj.done(now):
                self._finish_trajectory()
        elif self._mode == "position":
            self._track_goal(dt)
        if self.follows:
            self._step_psm(dt)
        else:
            self._step_mtm(dt, now)

    def _finish_trajectory(self):
        homing = self._traj.homing
        self._goal_p, self._goal_q = self._traj.p1, self._traj.q1
        self._traj = None
        self._mode = "position"
        self._busy = False
        if homing:
            self._homed = True  # EnterHomed: PID on, holding the home pose
        else:
            self._writers["goal_reached"].write(Bool(data=True))
        self._publish_operating_state()

    def _track_goal(self, dt):
        """First-order toward the stored goal, rate-limited in translation and rotation."""
        if self._sp_p == self._goal_p and self._sp_q == self._goal_q:
            return
        d = sub(self._goal_p, self._sp_p)
        dist = norm(d)
        step = min(dist * min(1.0, dt / self.p.track_time), self.p.max_speed * dt)
        # Within a nanometre / nanoradian it is there: an exact rest lets the steps idle cheaply.
        self._sp_p = self._goal_p if dist < 1e-9 else add(self._sp_p, scale(d, step / dist))
        angle = qangle(self._sp_q, self._goal_q)
        if angle < 1e-9:
            self._sp_q = self._goal_q
        else:
            turn = min(angle * min(1.0, dt / self.p.track_time), self.p.max_angular_speed * dt)
            self._sp_q = slerp(self._sp_q, self._goal_q, turn / angle)

    def _step_psm(self, dt):
        if self._mode == "free":
            self._sp_p, self._sp_q = self._meas_p, self._meas_q  # no effort: nothing pulls it
        if (self._meas_p == self._sp_p and self._meas_q == self._sp_q
                and self._jaw_meas == self._jaw_sp and (self._mode == "idle" or self._jaw_sp == self._jaw_goal)):
            self._v = self._w = (0.0, 0.0, 0.0)
            return
        a = min(1.0, dt / self.p.lag_time)
        p = add(self._meas_p, scale(sub(self._sp_p, self._meas_p), a))
        q = slerp(self._meas_q, self._sp_q, a)
        if norm(sub(self._sp_p, p)) < 1e-9 and qangle(q, self._sp_q) < 1e-9:
            p, q = self._sp_p, self._sp_q
        self._v = scale(sub(p, self._meas_p), 1.0 / dt)
        self._w = scale(rotate(self._meas_q, to_rotvec(qmul(qconj(self._meas_q), q))), 1.0 / dt)
        self._meas_p, self._meas_q = p, q
        if self._mode != "idle":
            d, limit = self._jaw_goal - self._jaw_sp, self.p.jaw_speed * dt
            self._jaw_sp = self._jaw_goal if abs(d) <= limit else self._jaw_sp + math.copysign(limit, d)
        self._jaw_meas += (self._jaw_sp - self._jaw_meas) * a
        if abs(self._jaw_sp - self._jaw_meas) < 1e-9:
            self._jaw_meas = self._jaw_sp

    def _step_mtm(self, dt, now):
        p, v, m = self._meas_p, self._v, self.p.mass
        if self._mode in ("position", "trajectory"):
            act = sub(scale(sub(self._sp_p, p), self.p.kp), scale(v, self.p.kd))
        elif self._mode == "effort":
            act = self._wrench if self._cf_absolute else rotate(self._meas_q, self._wrench)
        else:
            act = (0.0, 0.0, 0.0)
        self._applied = act
        force = add(act, scale(v, -self.p.damping))
        if self._mode != "idle" and not self._gravity_compensation:
            force = add(force, (0.0, 0.0, -m * self.p.gravity))
        if self._hand:
            force = add(force, self._hand_force(now, p))
            self._hand_twist(now)
        if self._mode in ("position", "trajectory") and not (self._hand and len(self._hand) > 3):
            # The wrist is position-controlled too (a move_cp turns the handle): its dynamics are
            # not simulated, its orientation is the setpoint's.
            self._meas_q = self._sp_q
        v = add(v, scale(force, dt / m))
        p = add(p, scale(v, dt))
        # The handle's mechanical stops.
        lo, hi = sub(self.home_p, (self.p.workspace,) * 3), add(self.home_p, (self.p.workspace,) * 3)
        clamped = tuple(min(h, max(l, x)) for x, l, h in zip(p, lo, hi))
        v = tuple(0.0 if c != x else vi for c, x, vi in zip(clamped, p, v))
        self._meas_p, self._v = clamped, v

    def _hand_force(self, now, p):
        amplitude, frequency = self._hand[0], self._hand[1]
        axis = tuple(self._hand[2]) if len(self._hand) > 2 else (1.0, 0.0, 0.0)
        phase = math.sin(2.0 * math.pi * frequency * (now - self._t0))
        self._gripper = 0.5 + 0.2 * phase
        target = add(self.home_p, scale(axis, amplitude * phase))
        return scale(sub(target, p), self.p.hand_stiffness)


    def _hand_twist(self, now):
        """A hand that also turns the handle (the 4th entry: amplitude in rad about z, in phase with
        the translation): the wrist's dynamics are not simulated, its orientation is the hand's."""
        if len(self._hand) < 4:
            return
        amplitude, frequency = self._hand[3], self._hand[1]
        omega = 2.0 * math.pi * frequency
        angle = amplitude * math.sin(omega * (now - self._t0))
        self._meas_q = qmul(self.home_q, from_rotvec((0.0, 0.0, angle)))
        self._w = rotate(self.home_q, (0.0, 0.0, amplitude * omega * math.cos(omega * (now - self._t0))))


class _Muted:
    """Stands for a writer nobody reads."""

    @staticmethod
    def write(sample):
        pass


def _pose(p, q):
    return Pose(position=Point(*p), orientation=Quaternion(*q))


def summary(value):
    """A short text of a command's value (for --echo)."""
    if isinstance(value, PoseStamped):
        pp, o = value.pose.position, value.pose.orientation
        return f"p=[{pp.x:.6g},{pp.y:.6g},{pp.z:.6g}] q=[{o.x:.6g},{o.y:.6g},{o.z:.6g},{o.w:.6g}]"
    if isinstance(value, WrenchStamped):
        f = value.wrench.force
        return f"f=[{f.x:.6g},{f.y:.6g},{f.z:.6g}]"
    if isinstance(value, JointState):
        return "position=[" + ",".join(f"{x:.6g}" for x in value.position) + "]"
    if isinstance(value, StringStamped):
        return value.string
    if isinstance(value, Bool):
        return str(value.data).lower()
    return ""


# --- the command ---

STDIN_ACTIONS = """actions, one a line on standard input:
  fault [WHY]                        FAULT with WHY on ARM/error
  press|release|tap BUTTON           console Joy [1]/[0]/[2]; BUTTON: clutch operator_present camera
  pause-publishing | resume-publishing
  invalid-stamps on|off | freeze-stamps on|off
  cannula ready|not-ready            (PSM) Cartesian commands taken or refused
  state                              print the operating state
  quit"""


def _act(sim, line):
    words = line.split()
    if not words:
        return True
    verb, rest = words[0], words[1:]
    on = rest[:1] == ["on"]
    if verb == "quit":
        return False
    if verb == "fault":
        sim.fault(" ".join(rest) or "simulated fault")
    elif verb in ("press", "release", "tap") and rest:
        getattr(sim, verb)(rest[0])
    elif verb == "pause-publishing":
        sim.pause_publishing()
    elif verb == "resume-publishing":
        sim.resume_publishing()
    elif verb == "invalid-stamps":
        sim.set_invalid_stamps(on)
    elif verb == "freeze-stamps":
        sim.freeze_stamps(on)
    elif verb == "cannula" and rest:
        sim.set_cannula_ready(rest[0] == "ready")
    elif verb == "state":
        print("state " + " ".join(str(x) for x in sim.operating_state()), flush=True)
    else:
        print(STDIN_ACTIONS, file=sys.stderr, flush=True)
    return True


def _parse(argv):
    ap = argparse.ArgumentParser(description="A simulated dVRK 2.4 arm over ROS 2 DDS (Cyclone DDS).",
                                 epilog=STDIN_ACTIONS, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--arm", required=True, help="arm name, the topic namespace (MTML, MTMR, PSM1, ...)")
    ap.add_argument("--domain", type=int, default=int(os.environ.get("SAW_TEST_DOMAIN", "0")),
                    help="DDS domain (ROS_DOMAIN_ID); default $SAW_TEST_DOMAIN or 0")
    ap.add_argument("--kind", choices=("mtm", "psm", "ecm"), help="default: mtm for MTM*, ecm for ECM, else psm")
    ap.add_argument("--home-q", type=float, nargs=4, metavar=("X", "Y", "Z", "W"),
                    help="the home orientation (an ECM's: the camera frame), default identity")
    ap.add_argument("--rate", type=float, default=100.0, help="state publishing rate, Hz (dVRK default 100)")
    ap.add_argument("--namespace", default="", help="ROS namespace before the arm name")
    ap.add_argument("--console", action=argparse.BooleanOptionalAction, default=None,
                    help="publish rt/console/{clutch,operator_present,camera} (default: for an MTM)")
    ap.add_argument("--power-time", type=float, default=Params.power_time)
    ap.add_argument("--home-time", type=float, default=Params.home_time)
    ap.add_argument("--invalid-stamps", action="store_true", help="stamp 0 on every state sample")
    ap.add_argument("--freeze-stamps", action="store_true", help="one stamp repeated on every state sample")
    ap.add_argument("--pause-publishing-at", type=float, metavar="T", help="stop the state streams T s after start")
    ap.add_argument("--fault-at", type=float, metavar="T", help="FAULT T s after start")
    ap.add_argument("--cannula-not-ready", action="store_true", help="(PSM) refuse Cartesian commands")
    ap.add_argument("--hand", metavar="AMPLITUDE,FREQUENCY", help="(MTM) a scripted hand moving the handle along x")
    ap.add_argument("--echo", action="store_true", help="print every command received")
    return ap.parse_args(argv)


def main(argv=None):
    a = _parse(argv)
    params = Params(power_time=a.power_time, home_time=a.home_time)
    hand = tuple(float(x) for x in a.hand.split(",")) if a.hand else None
    echo = (lambda c: print(f"cmd {c.time:.6f} {c.topic} {summary(c.value)}", flush=True)) if a.echo else None
    sim = SimArm(a.arm, a.domain, kind=a.kind, rate=a.rate, namespace=a.namespace, console=a.console,
                 params=params, hand=hand, echo=echo, home_q=a.home_q)
    sim.set_invalid_stamps(a.invalid_stamps)
    sim.freeze_stamps(a.freeze_stamps)
    sim.set_cannula_ready(not a.cannula_not_ready)

    def leave(signum, frame):
        raise SystemExit(0)

    signal.signal(signal.SIGTERM, leave)
    timers = []
    if a.pause_publishing_at is not None:
        timers.append(threading.Timer(a.pause_publishing_at, sim.pause_publishing))
    if a.fault_at is not None:
        timers.append(threading.Timer(a.fault_at, sim.fault, args=("scripted fault (--fault-at)",)))
    try:
        with sim:
            for tm in timers:
                tm.daemon = True
                tm.start()
            print(f"ready {a.arm} {sim.kind} domain {a.domain}", flush=True)
            for line in sys.stdin:
                if not _act(sim, line):
                    return 0
            threading.Event().wait()  # stdin closed: run until a signal
    except KeyboardInterrupt:
        pass
    finally:
        for tm in timers:
            tm.cancel()
    return 0


if __name__ == "__main__":
    sys.exit(main())
