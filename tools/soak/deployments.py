"""The soak's teleoperations (simulated, CANopen, bilateral; and in the PREEMPT_RT guest a Falcon
over USB), each a saw-rt process of its own with its gateway beside it, as a lab runs them. Names
carry a prefix, so that their segments (/dev/shm/saw.<component>) and the CAN bus do not meet
another run's."""
import os
import re
import subprocess
import time

MASTER = """  - name: {p}master
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params:
      model: omni
      hand: {{type: sinusoid, amplitude: [0.03, 0.0, 0.0], frequency: 0.5, stiffness: 200, damping: 2}}
"""

TELEOP = """  - name: {p}teleop
    type: teleop
    task: {{period: 1ms, priority: 79, offset: 300us}}
    params:
      gains: {{master: 300, slave: 300}}
      force_limits: {{master: 3.0, slave: 3.0}}
      stale_timeout: 20ms
{extra}
connections:
  - {{client: {p}teleop, required: master, server: {p}master, provided: arm}}
  - {{client: {p}teleop, required: slave, server: {p}slave, provided: arm}}
"""

SIM = """deployment: {{name: {p}sim}}
components:
""" + MASTER + """  - name: {p}slave
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params: {{model: omni}}
""" + TELEOP + """exports:
  - {{component: {p}master, provided: arm}}
  - {{component: {p}slave, provided: arm}}
  - {{component: {p}teleop, provided: teleop}}
record: {{columns: [{p}master.measured_cp, {p}slave.measured_cp, {p}teleop.tracking_error]}}
"""

JOINT = """        {name}:
          node: {node}
{xyz}          axis: {axis}
          counts_per_revolution: 4096
          gear_ratio: 100
          rated_torque: 0.318
          max_torque: 2.0
          min: {lo}
          max: {hi}
          max_velocity: 3.0
{offset}"""

CANOPEN = """deployment: {{name: {p}can}}
components:
""" + MASTER + """  - name: {p}slave
    type: canopen_arm
    task: {{period: 1ms, priority: 80}}
    params:
      bus: {bus}
      mode: cst
      start_enabled: true
      heartbeat: {{period: 50ms, timeout: 150ms}}
      master_heartbeat: {{period: 50ms, timeout: 150ms}}
      abort_connection: quick_stop
      command_timeout: 20ms
      rpdo_deadline: 5ms
      max_force: 3.3
      chain: [yaw, shoulder_pitch, elbow_pitch]
      tip: {{xyz: [0.133, 0, 0]}}
      joints:
{joints}""" + TELEOP + """exports:
  - {{component: {p}master, provided: arm}}
  - {{component: {p}slave, provided: arm}}
  - {{component: {p}teleop, provided: teleop}}
record: {{columns: [{p}master.measured_cp, {p}slave.measured_cp, {p}teleop.tracking_error]}}
"""

BILATERAL = """deployment: {{name: {p}bil}}
components:
  - name: {p}master
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params:
      model: omni
      hand: {{type: reach, targets: [[0, 0, -0.02], [0.02, 0, -0.02], [0.02, 0, 0]], reach_time: 0.8, dwell: 0.7,
             stiffness: 200, damping: 1}}
  - name: {p}slave
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params:
      model: omni
      wall: {{point: [0, 0, -0.012], normal: [0, 0, 1], stiffness: 100, damping: 0}}
  - name: {p}port
    type: passivity_port
    task: {{period: 1ms, priority: 79, offset: 200us}}
  - name: {p}link
    type: delay
    task: {{period: 1ms, priority: 79, offset: 250us}}
    params: {{delay: 50ms, jitter: 10ms, loss: 0.1, commands: {{delay: 50ms, jitter: 10ms, loss: 0.1}}}}
  - name: {p}teleop
    type: teleop
    task: {{period: 1ms, priority: 79, offset: 300us}}
    params:
      law: passive_bilateral
      gains: {{master: 600, slave: 600}}
      damping: 1.5
      force_limits: {{master: 3.0, slave: 3.0}}
      stale_timeout: 200ms
connections:
{bilateral_connections}
exports:
  - {{component: {p}master, provided: arm}}
  - {{component: {p}slave, provided: arm}}
  - {{component: {p}teleop, provided: teleop}}
record: {{columns: [{p}master.measured_cp, {p}slave.measured_cp]}}
"""


# The Falcon over real USB (the guest's gadget, tests/kernel/falcon_gadget.py) as the master of a
# simulated Omni; an unplugged Falcon is looked for again every 500 ms (`reconnect`). The guest's
# emulated CPUs stall its tasks for tens of ms: exchanges may go unanswered for 200 cycles there.
FALCON = """deployment: {{name: {p}fal}}
components:
  - name: {p}master
    type: falcon
    task: {{period: 1ms, priority: 80}}
    params:
      transport: usb
      firmware: {firmware}
      usb: {{bus: -1, index: 0, exchange_timeout_ms: 20}}
      max_missed: 200
      reconnect: 500ms
      max_force: 8.0
      workspace: {{min: [-0.06, -0.06, -0.06], max: [0.06, 0.06, 0.06]}}
  - name: {p}slave
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params: {{model: omni}}
""" + TELEOP + """exports:
  - {{component: {p}master, provided: arm}}
  - {{component: {p}slave, provided: arm}}
  - {{component: {p}teleop, provided: teleop}}
record: {{columns: [{p}master.measured_cp, {p}slave.measured_cp, {p}teleop.tracking_error]}}
"""

# The device an operator enables first (it configures drives or homes on that enable).
DEVICE_FIRST = {"canopen": "slave", "falcon": "master"}


def loosen(text):
    """The timing limits for a machine that stalls its tasks for tens to hundreds of ms (the
    software-emulated PREEMPT_RT guest), as its other checks loosen them: the faults injected are
    under test there, not the timing (a late loop's FAULT is the host soak's and the starved
    teleoperation test's). Tasks: 500 missed periods in a row or 90 %, and 2 s of history (the
    recorder's collector stalls for hundreds of ms there, past the default 256 ms); inputs, the arm's commands
    and feedback 500 ms; the drives' RPDO deadline and heartbeats 500 ms; the Falcon's unanswered
    exchanges 1000 in a row (the guest's gadget answers some 25–100 a second)."""
    edits = [("task: {period: 1ms, ", "task: {period: 1ms, deadline: {in_a_row: 500, share: 0.9}, history: 2s, "),
             ("stale_timeout: 20ms", "stale_timeout: 500ms"), ("rpdo_deadline: 5ms", "rpdo_deadline: 500ms"),
             ("timeout: 150ms}", "timeout: 500ms}"),
             ("      command_timeout: 20ms\n", "      command_timeout: 500ms\n      feedback_timeout: 500ms\n"),
             ("max_missed: 200", "max_missed: 1000")]
    for old, new in edits:
        text = text.replace(old, new)
    return text


def joints():
    spec = [("yaw", 1, "", "[0, 0, 1]", -1.7, 1.7, ""), ("shoulder_pitch", 2, "", "[0, 1, 0]", -1.2, 1.75, ""),
            ("elbow_pitch", 3, "          xyz: [0.133, 0, 0]\n", "[0, 1, 0]", -0.2, 2.6, "          offset: 1.2\n")]
    return "".join(JOINT.format(name=n, node=k, xyz=x, axis=a, lo=lo, hi=hi, offset=o) for n, k, x, a, lo, hi, o in spec)


def bilateral_connections(src, p):
    """The shipped bilateral deployment's connections, its names prefixed (the port and link chain
    is the shipped file's: the soak runs what users run)."""
    lines, on = [], False
    for line in open(os.path.join(src, "config", "teleop-bilateral-sim.yaml")):
        if line.startswith("connections:"):
            on = True
            continue
        if on:
            if line.strip() and not line.startswith(" "):
                break
            if line.strip().startswith("- {"):
                for key in ("client", "server"):
                    line = line.replace(f"{key}: ", f"{key}: {p}")
                lines.append(line.rstrip())
    return "\n".join(lines)


class Deployment:
    """One saw-rt process (its log and recording in `run_dir`), its gateway and, for the CANopen
    arm, the drives' process."""

    def __init__(self, kind, prefix, bin_dir, src, run_dir, domain, can_bus=None, firmware=None, loose=False):
        """`can_bus`: the CANopen arm's bus (a private virtual one by default); `firmware`: the
        Falcon's firmware file (the falcon deployment); `loose`: timing limits for an emulated
        machine (loosen())."""
        self.kind, self.p, self.bin, self.dir, self.domain = kind, prefix, bin_dir, run_dir, domain
        self.bus = can_bus or f"virtual:{prefix}bus"
        text = {"sim": SIM, "canopen": CANOPEN, "bilateral": BILATERAL, "falcon": FALCON}[kind]
        self.yaml = os.path.join(run_dir, f"{kind}.yaml")
        text = text.format(p=prefix, extra="", joints=joints() if kind == "canopen" else "", bus=self.bus,
                           firmware=firmware,
                           bilateral_connections=bilateral_connections(src, prefix) if kind == "bilateral" else "")
        with open(self.yaml, "w") as f:
            f.write(loosen(text) if loose else text)
        self.exports = {"sim": ["master", "slave", "teleop"], "canopen": ["master", "slave", "teleop"],
                        "bilateral": ["master", "slave", "teleop"], "falcon": ["master", "slave", "teleop"]}[kind]
        # The devices an operator enables before the teleoperation (an enable of an enabled
        # device does nothing): the one that configures or homes on it first.
        first = DEVICE_FIRST.get(kind, "master")
        self.devices = [prefix + first] + [prefix + x for x in ("master", "slave") if x != first]
        self.slow_enable = kind in DEVICE_FIRST
        self.exports = [prefix + e for e in self.exports]
        self.teleop = prefix + "teleop"
        self.rt = self.gw = self.drives = None
        self.gw_starts = self.drive_starts = 0

    def log(self, what):
        return os.path.join(self.dir, f"{self.kind}.{what}")

    def start_drives(self):
        self.drive_starts += 1
        out = open(self.log(f"drives{self.drive_starts}.log"), "w")
        self.drives = subprocess.Popen(
            [os.path.join(self.bin, "saw-can-sim"), "--bus", self.bus, "--node", "1", "--node", "2",
             "--node", "3", "--load-inertia", "0.002", "--friction", "2e-6", "--priority", "70"],
            stdout=out, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + 10
        while "drives on" not in open(out.name).read():
            if self.drives.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"saw-can-sim did not start: {open(out.name).read()[-500:]}")
            time.sleep(0.05)

    def start(self):
        if self.kind == "canopen":
            self.start_drives()
        self.rt = subprocess.Popen([os.path.join(self.bin, "saw-rt"), self.yaml, "--record", self.log("csv")],
                                   stdout=open(self.log("out"), "w"), stderr=open(self.log("err"), "w"))
        self.start_gateway()

    def start_gateway(self):
        self.gw_starts += 1
        args = [os.path.join(self.bin, "saw-gateway"), "--domain", str(self.domain), "--wait", "20",
                "--name", f"{self.p}{self.kind}-gw"]
        for e in self.exports:
            args += ["--attach", e]
        self.gw = subprocess.Popen(args, stdout=open(self.log(f"gw{self.gw_starts}.out"), "w"),
                                   stderr=subprocess.STDOUT)

    def drives_left(self):
        """After stop(): each CAN drive's NMT and CiA 402 state as saw-can-sim's table at its exit
        says them, [(node, nmt, state)] (empty without drives, or when the table is missing)."""
        if not self.drive_starts:
            return []
        text = open(self.log(f"drives{self.drive_starts}.log"), errors="replace").read()
        return re.findall(r"^\s*([123])\s+(\S+)\s+(.+?)\s{2,}-?\d+\s+-?\d+", text, re.M)

    def stop(self):
        """SIGINT to saw-rt (its orderly stop: every device through its safe state, the summary);
        then the gateway and the drives."""
        import signal
        rc = None
        if self.rt and self.rt.poll() is None:
            self.rt.send_signal(signal.SIGINT)
            try:
                rc = self.rt.wait(30)
            except subprocess.TimeoutExpired:
                self.rt.kill()
                rc = "hung"
        else:
            rc = self.rt.returncode if self.rt else None
        for p in (self.gw, self.drives):
            if p and p.poll() is None:
                p.send_signal(signal.SIGINT)
                try:
                    p.wait(10)
                except subprocess.TimeoutExpired:
                    p.kill()
        return rc
