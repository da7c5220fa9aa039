"""One bilateral teleoperation run on the stepped clock, and its figures (imported by bilateral.py
and by the verdict test). The master is a simulated Omni-like device held by a human-like hand
(minimum-jerk reaches with dwell and physiological tremor); the slave pushes into a stiff virtual
wall; a passivity port sits beside the master and a delay task (delay, jitter, loss each way)
between it and the teleoperation task, which runs beside the slave."""
import dataclasses
import pathlib
import subprocess

import numpy as np

WALL_DEPTH = 0.012  # m below the start: the hand reaches 20 mm down, the wall is 12 mm down
WALL_STIFFNESS = 100.0  # N/m: tissue-like; a 1000 N/m wall is measured beside it
SETTLE = 1.0  # s ignored at the start of each run
SATURATION_RUN = 0.1  # s: a force held at its limit longer than this is a saturated run
FORCE_LIMIT = 3.0  # N, both sides
ENERGY_GROWTH = 0.05  # J given out by the channel over the run's second half: an active channel
# The same on real threads over two hosts, from each host's recording: a force and a velocity there
# may be a cycle apart, which makes a passive channel seem to give out ~0.01 J/s; a growing one
# gives out joules.
SPLIT_ENERGY_GROWTH = 0.5
# N RMS of a force about its mean in a dwell: an oscillating channel. Five times what the hand's
# tremor gives through the coupling (~0.2 N), a third of the force limit: the uncontrolled
# coupling at 50 ms and the paper's law at 20 ms ring at 2.7–2.8 N, the passive laws stay under
# 0.35 N.
OSCILLATION = 1.0


# Minimum-jerk reaches between targets with dwell, physiological tremor on top, through a grip.
# Each leg (origin → the three targets → origin) a reach of 0.8 s, then a dwell of 0.7 s.
HAND = ("{type: reach, targets: [[0, 0, -0.02], [0.02, 0, -0.02], [0.02, 0, 0]], reach_time: 0.8, dwell: 0.7, "
        "stiffness: 200, damping: 1, tremor: {amplitude: 0.0003, frequency: 10}}")


LEG = 1.5  # s: a reach and its dwell
DWELL = (1.0, 1.5)  # s into each leg: the dwell, 0.2 s after the reach ended


def dwell_oscillation(t, *forces):
    """The largest RMS of a force about its own mean over one dwell, of the given sides (N). The
    hand holds still there but for its tremor (0.3 mm at 10 Hz: ~0.2 N through a 600 N/m coupling);
    a delayed coupling that rings or oscillates shows it here whatever its energy says."""
    worst = 0.0
    for k in range(int(t[-1] // LEG) + 1):
        m = (t >= max(k * LEG + DWELL[0], SETTLE)) & (t < k * LEG + DWELL[1])
        if m.sum() < 100:
            continue
        for f in forces:
            x = f[m] - f[m].mean(axis=0)
            worst = max(worst, float(np.sqrt(np.mean(np.sum(x ** 2, axis=1)))))
    return worst


def wall_yaml(stiffness: float) -> str:
    return f"{{point: [0, 0, {-WALL_DEPTH}], normal: [0, 0, 1], stiffness: {stiffness}, damping: 0}}"


@dataclasses.dataclass
class Law:
    key: str  # short name for tables
    label: str
    params: str  # the teleop's law and settings (YAML flow mapping entries)
    passivity: bool  # the master port's controller acts (else it only observes)
    port: str = ""  # the master port's other parameters (YAML flow mapping entries)


# One coupling stiffness (600 N/m, 1.5 N·s/m where the law has a damper): what differs is the
# feedback and the passivity. The paper's law, undamped, is stable here without delay only up to
# about 200 N/m: it runs at that.
LAWS = [
    Law("unilateral", "unilateral (position_position: no force feedback)",
        "law: position_position, stiffness: 600, damping: 1.5, force_limit: 3", False),
    Law("paper", "the paper's bilateral law (collaborative, k_m = k_s = 200 N/m)",
        "law: collaborative, gains: {master: 200, slave: 200}, force_limits: {master: 3, slave: 3}", False),
    Law("coupling", "the same coupling with damping, no passivity (passive_bilateral, passivity off)",
        "law: passive_bilateral, gains: {master: 600, slave: 600}, damping: 1.5, passivity: false, "
        "force_limits: {master: 3, slave: 3}", False),
    Law("wave", "wave variables (wave_variables, b = 3 N·s/m; velocities travel)",
        "law: wave_variables, impedance: 3, stiffness: 600, damping: 1.5, force_limit: 3", True,
        "scheme: wave, wave_impedance: 3"),
    Law("tdpa", "bilateral + time-domain passivity (passive_bilateral, ours)",
        "law: passive_bilateral, gains: {master: 600, slave: 600}, damping: 1.5, "
        "force_limits: {master: 3, slave: 3}", True),
]


@dataclasses.dataclass
class Result:
    tracking_rms: float  # m, free motion
    force_rms: float  # N, felt at the master vs the wall's at the slave, in contact
    felt_stiffness: float  # N/m, slope of felt force vs the hand-side penetration
    slave_stiffness: float  # N/m, the same at the slave
    channel_energy: float  # J, the most the network gave out beyond what it took in (its samples)
    physics_energy: float  # J, the same from the devices' physics: the motors' work on both arms
    physics_outflow: float  # J, the most the motors gave out over any one interval (physics)
    oscillation: float  # N, the largest RMS of either side's force about its mean in a dwell
    max_force: float  # N
    saturated_for: float  # s, the longest run of a force at its limit
    stable: bool
    why: str


def deployment(law: Law, delay_ms: float, loss: float, jitter_ms: float = 0.0, seed: int = 1,
               wall: float = WALL_STIFFNESS) -> str:
    link = f"delay: {delay_ms}ms, jitter: {jitter_ms}ms, loss: {loss}"
    # No network: the teleoperation reads the master's port directly (as in one process).
    direct = delay_ms == 0 and jitter_ms == 0 and loss == 0
    link_component = "" if direct else f"""
  - {{name: link, type: delay, task: {{period: 1ms}}, params: {{{link}, seed: {seed}, commands: {{{link}}}}}}}"""
    link_connection = "" if direct else """
  - {client: link, required: source, server: port, provided: arm}"""
    master_server = "port" if direct else "link"
    return f"""deployment: {{name: bilateral, clock: stepped}}
components:
  - {{name: master, type: sim_haptic_device, task: {{period: 1ms}}, params: {{model: omni, hand: {HAND}}}}}
  - {{name: slave, type: sim_haptic_device, task: {{period: 1ms}}, params: {{model: omni, wall: {wall_yaml(wall)}}}}}
  - {{name: port, type: passivity_port, task: {{period: 1ms}}, params: {{passivity: {str(law.passivity).lower()}{", " + law.port if law.port else ""}}}}}{link_component}
  - name: teleop
    type: teleop
    task: {{period: 1ms}}
    params: {{{law.params}, stale_timeout: 1s}}
connections:
  - {{client: port, required: device, server: master, provided: arm}}{link_connection}
  - {{client: teleop, required: master, server: {master_server}, provided: arm}}
  - {{client: teleop, required: slave, server: slave, provided: arm}}
record:
  columns: [master.measured_cp, master.measured_cv, slave.measured_cp, slave.measured_cv, teleop.slave_force, slave.wall_force, port.port_applied,
            master.servo_work, slave.servo_work]
"""


def hosts_deployment(law: Law, delay_ms: float, loss: float, jitter_ms: float = 0.0, addresses=None,
                     domain: int = 0, port: str = "port") -> str:
    """The same run placed on two hosts: "operator" (the master and its port) and "patient" (the
    slave, the network's delay task and the law). Without addresses both are this machine and the
    shared-memory bridge joins them; with addresses each host's gateway carries the link over DDS.
    `port` names the master's port (the component the operator exports: unique on a shared host)."""
    a = addresses or {}
    hosts = "\n".join(f"  {h}: {{{('address: ' + a[h]) if h in a else ''}}}" for h in ("operator", "patient"))
    gateway = f"gateway: {{domain: {domain}, security: none}}\n" if a else ""
    link = f"delay: {delay_ms}ms, jitter: {jitter_ms}ms, loss: {loss}"
    return f"""deployment: {{name: bilateral-hosts}}
hosts:
{hosts}
{gateway}components:
  - {{name: master, host: operator, type: sim_haptic_device, task: {{period: 1ms, priority: 80}}, params: {{model: omni, hand: {HAND}}}}}
  - {{name: {port}, host: operator, type: passivity_port, task: {{period: 1ms, priority: 79}}, params: {{passivity: {str(law.passivity).lower()}{", " + law.port if law.port else ""}}}}}
  - {{name: slave, host: patient, type: sim_haptic_device, task: {{period: 1ms, priority: 80}}, params: {{model: omni, wall: {wall_yaml(WALL_STIFFNESS)}}}}}
  - {{name: link, host: patient, type: delay, task: {{period: 1ms, priority: 79}}, params: {{{link}, seed: 1, commands: {{{link}}}}}}}
  - name: teleop
    host: patient
    type: teleop
    task: {{period: 1ms, priority: 79}}
    params: {{{law.params}, stale_timeout: 500ms, startup_timeout: 10s}}
connections:
  - {{client: {port}, required: device, server: master, provided: arm}}
  - {{client: link, required: source, server: {port}, provided: arm}}
  - {{client: teleop, required: master, server: link, provided: arm}}
  - {{client: teleop, required: slave, server: slave, provided: arm}}
record:  # each host records its own components' columns
  columns: [master.measured_cp, master.measured_cv, {port}.port_applied, slave.measured_cp, slave.measured_cv,
            teleop.slave_force, slave.wall_force, teleop.tracking_error]
"""


def longest_run(mask) -> int:
    """The most consecutive True samples."""
    longest, run_ = 0, 0
    for x in mask:
        run_ = run_ + 1 if x else 0
        longest = max(longest, run_)
    return longest


def side_verdict(forces, power, dt):
    """(longest run at the force limit in s, energy given out over the second half in J) of one port."""
    longest = longest_run(np.linalg.norm(forces, axis=1) >= FORCE_LIMIT - 1e-3)
    energy = np.cumsum(power) * dt
    half = len(energy) // 2
    return longest * dt, float(energy[-1] - energy[half]) if len(energy) else 0.0


def split_figures(operator, patient, port: str = "port"):
    """The verdict of a run recorded on two hosts (each its own clock: no sample is paired across
    them): saturation at either port, energy given out at both ports over their second halves,
    tracking as the law saw it."""
    def vec(d, name):  # a row not recorded yet (the other host's data) reads as nothing
        return np.nan_to_num(np.stack([d[name.replace(".", "") + a] for a in "xyz"], 1))

    dt = 1e-3
    sat_m, grow_m = side_verdict(vec(operator, f"{port}.port_applied."),
                                 np.einsum("ij,ij->i", vec(operator, f"{port}.port_applied."),
                                           vec(operator, "master.measured_cv.v")), dt)
    sat_s, grow_s = side_verdict(vec(patient, "teleop.slave_force."),
                                 np.einsum("ij,ij->i", vec(patient, "teleop.slave_force."),
                                           vec(patient, "slave.measured_cv.v")), dt)
    why = []
    if max(sat_m, sat_s) > SATURATION_RUN:
        why.append(f"forces at their limit for {max(sat_m, sat_s) * 1e3:.0f} ms")
    if grow_m + grow_s > SPLIT_ENERGY_GROWTH:
        why.append("the channel's energy grows")
    t = patient["time"]
    e = patient["teleoptracking_error"][t >= t[0] + SETTLE]
    tracking = float(np.sqrt(np.mean(e ** 2))) if len(e) else float("nan")
    return not why, "; ".join(why) or "stable", tracking, grow_m + grow_s


def run(saw_rt: pathlib.Path, work: pathlib.Path, law: Law, delay_ms: float, loss: float, seconds: float = 8.0,
        jitter_ms: float = 0.0, wall: float = WALL_STIFFNESS):
    name = f"{law.key}_{delay_ms:g}ms_{int(loss * 100)}pct_{jitter_ms:g}j_{wall:g}w"
    cfg = work / f"{name}.yaml"
    csv = work / f"{name}.csv"
    cfg.write_text(deployment(law, delay_ms, loss, jitter_ms, wall=wall))
    subprocess.run([str(saw_rt), str(cfg), "--duration", str(seconds), "--record", str(csv)], check=True,
                   stdout=subprocess.DEVNULL)
    return np.genfromtxt(csv, delimiter=",", names=True)


def col(d, name, axis):
    return d[name.replace(".", "") + axis]


def figures(d, wall: float = WALL_STIFFNESS) -> Result:
    t = d["time"]
    dt = float(np.median(np.diff(t)))
    xm = np.stack([col(d, "master.measured_cp.", a) for a in "xyz"], 1)
    xs = np.stack([col(d, "slave.measured_cp.", a) for a in "xyz"], 1)
    vm = np.stack([col(d, "master.measured_cv.v", a) for a in "xyz"], 1)
    vs = np.stack([col(d, "slave.measured_cv.v", a) for a in "xyz"], 1)
    fm = np.stack([col(d, "port.port_applied.", a) for a in "xyz"], 1)
    fs = np.stack([col(d, "teleop.slave_force.", a) for a in "xyz"], 1)
    fw = np.stack([col(d, "slave.wall_force.", a) for a in "xyz"], 1)
    keep = t >= SETTLE
    offset = xs[0] - xm[0]  # the law engages with the error cancelled
    contact = keep & (fw[:, 2] > 0.05)
    free = keep & (fw[:, 2] == 0)
    err = np.linalg.norm(xs - xm - offset, axis=1)
    tracking = float(np.sqrt(np.mean(err[free] ** 2))) if free.any() else float("nan")
    # Felt: the force on the master along the wall's normal against how far the hand is "in" the
    # wall, mapped to the master's side; the slave's: the wall's force against its penetration.
    wall_s = xs[0, 2] - WALL_DEPTH
    pen_m = (wall_s - offset[2]) - xm[:, 2]
    pen_s = wall_s - xs[:, 2]
    felt = fm[:, 2]
    force_rms = float(np.sqrt(np.mean((felt[contact] - fw[contact, 2]) ** 2))) if contact.any() else float("nan")

    def slope(x, y, mask):
        m = mask & (x > 0)
        if m.sum() < 50 or np.ptp(x[m]) < 1e-4:
            return float("nan")
        return float(np.polyfit(x[m], y[m], 1)[0])

    felt_k = slope(pen_m, felt, contact)
    slave_k = slope(pen_s, fw[:, 2], contact)
    # The network's output power: the forces it applies against the velocities at both ports.
    power = np.einsum("ij,ij->i", fm, vm) + np.einsum("ij,ij->i", fs, vs)
    energy = np.cumsum(power) * dt
    channel = float(np.max(energy))
    fmag = np.maximum(np.linalg.norm(fm, axis=1), np.linalg.norm(fs, axis=1))
    saturated = longest_run(fmag >= FORCE_LIMIT - 1e-3) * dt
    # A passive network gives out no more than it stores (½·k·e² at the force limit: ~10 mJ); one
    # that keeps giving energy over the second half of the run is active, and its motion grows
    # until something saturates.
    half = len(energy) // 2
    grows = float(energy[-1] - energy[half]) > ENERGY_GROWTH
    why = []
    if saturated > SATURATION_RUN:
        why.append(f"forces at their limit for {saturated * 1e3:.0f} ms")
    if grows:
        why.append("the channel's energy grows")
    oscillation = dwell_oscillation(t, fm, fs)
    if oscillation > OSCILLATION:
        why.append(f"oscillating in the dwells ({oscillation:.2f} N RMS)")
    if not np.isfinite(xm).all():
        why.append("positions not finite")
    physics, outflow = physics_energies(d)
    return Result(tracking, force_rms, felt_k, slave_k, channel, physics, outflow, oscillation,
                  float(np.max(fmag)), saturated, not why, "; ".join(why) or "stable")


def physics_energies(d):
    """(most, most over one interval) of the energy the channel's motors gave the arms, J: from
    each simulated device's physics (its applied force along its tip's path, at its substeps), not
    from the force and velocity samples a passivity controller bounds. A passive channel gives out
    nothing beyond what it took in (the first is at most ~0), and over one interval no more than
    its coupling stored (½·F²/k: 7.5 mJ at 3 N and 600 N/m)."""
    w = d["masterservo_work"] + d["slaveservo_work"]
    return float(np.max(w)), float(np.max(w - np.minimum.accumulate(w)))
