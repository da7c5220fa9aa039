"""saw-rt's CANopen master against drives it did not write: python `canopen` plays CiA 402 drives.

Real processes: saw-socketcand serves a virtual bus of this test's own on 127.0.0.1; the drives
(python_drive.py: python canopen's LocalNode with CiA 301/402 behaviour written from the
standards) are on it through python-can's socketcand interface; saw-rt runs a one-drive
deployment (`canopen_drive`, CSP, 10 ms) on the same bus. Each case is what a real drive does:

  kill9        saw-rt killed with SIGKILL while the drive is enabled: the drive's own heartbeat
               consumer (0x1016, written by the master at start-up) sees the master gone and
               stops it as 0x6007 says (quick stop by default)
  boot_fault   the drive is in FAULT when the master starts: a fault reset (rising edge of bit 7)
               clears it and the drive is enabled (and the deployment's SDO writes reached it)
  stuck_fault  the same, but the fault stays: a bounded number of resets, then FAULT naming the
               node and the error code (0x603F)
  stuck_enable the drive never leaves "switched on": FAULT naming that state
  wrong_mode   0x6061 never shows the mode written to 0x6060: never enabled, FAULT naming both
  pre_op       the enabled drive goes pre-operational by itself: FAULT naming the NMT state
  warning      an EMCY warning (0x4210, the drive stays enabled): logged in hex with its name,
               counted on the component's status, no FAULT
  error_emcy   an EMCY with the drive in FAULT: the arm's FAULT names the code and its name
  rpdo_deadline saw-rt stopped (SIGSTOP) longer than the drive's RPDO deadline (0x1400:05, written
               from rpdo_deadline) but shorter than its heartbeat consumer time: the drive sees the
               RPDOs stop (EMCY 0x8250, 0x6007's quick stop); running again, saw-rt faults on that
               EMCY naming the drive
  identity     the drive's vendor-ID is not the EDS's: start-up fails (exit 1) naming both
  reboot       the enabled drive reboots (a power cycle: its object dictionary back to the EDS's
               defaults, pre-operational, a boot-up message): saw-rt's FAULT names the reboot;
               an `enable` sent as a lab sends it (sawctl, through the deployment's gateway) makes
               the master configure the drive again (PDO maps, 0x1017, 0x1016, 0x6007, 0x6060,
               NMT start) and enable it; a `servo_jp` then reaches the drive's 0x607A

Usage: canopen_python_drive_test.py <saw-rt> <saw-socketcand> <sawctl> <sim_drive.eds> [case ...]
Exits 77 (skipped) when the tools venv has no `canopen`.
"""

import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time

try:
    import canopen
except ImportError as e:
    print(f"SKIP: python canopen is not installed in this venv ({e}); tools/requirements.txt has it")
    sys.exit(77)

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "can"))
sys.path.insert(0, HERE)
from child_tools import check, fail, start_socketcand  # noqa: E402
from python_drive import PythonDrive  # noqa: E402

SAW_RT, SERVER, SAWCTL, EDS = sys.argv[1], sys.argv[2], sys.argv[3], os.path.abspath(sys.argv[4])
NODE = 5

DEPLOYMENT = """
deployment: {{name: python-drive, clock: real}}
components:
  - name: axis
    type: canopen_drive
    task: {{period: 10ms, priority: 0}}
    params:
      bus: virtual:{bus}
      mode: csp
      start_enabled: true
      # python's scheduling, not the drive, sets these: generous, the path is under test (stalls
      # of a second have been seen with other tests running)
      heartbeat: {{period: 100ms, timeout: 3s}}
      feedback_timeout: 3s
      rpdo_deadline: {deadline}
{master}
      transition_timeout: 1s
      startup: {{boot_timeout: 5s, sdo_timeout: 2s, operational_timeout: 5s}}
      joint: j
      node: {node}
      counts_per_revolution: 4096
      rated_torque: 0.3
      min: -100
      max: 100
{extra}{top}"""


class Case:
    """One run: the bus, saw-socketcand, the python drive, saw-rt."""

    # The master's heartbeat as the drive watches it: generous (above), except where the
    # default (100 ms, 300 ms) is under test.
    def __init__(self, name, extra="", default_master=False, top="", deadline="3s", **drive_options):
        self.name = name
        self.bus = f"sawpydrive{os.getpid()}{name.replace('_', '')}"
        self.server, port = start_socketcand(SERVER, self.bus)
        self.network = canopen.Network()
        self.network.connect(interface="socketcand", host="127.0.0.1", port=port, channel=self.bus)
        time.sleep(0.2)  # saw-socketcand holds frames 50 ms after the handshake
        self.drive = PythonDrive(self.network, NODE, EDS, **drive_options)
        self.drive.boot()
        with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
            master = "" if default_master else "      master_heartbeat: {period: 100ms, timeout: 3s}\n"
            f.write(DEPLOYMENT.format(bus=self.bus, node=NODE, extra=extra, master=master, top=top,
                                      deadline=deadline))
            self.config = f.name
        self.rt = None

    def start(self, duration=None):
        args = [SAW_RT, self.config] + (["--duration", str(duration)] if duration else [])
        self.rt = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        # Read as they come, so that a case can wait for a line while saw-rt runs.
        self.lines = {"out": [], "err": []}
        self.readers = [threading.Thread(target=self._read, args=(stream, self.lines[key]), daemon=True)
                        for stream, key in ((self.rt.stdout, "out"), (self.rt.stderr, "err"))]
        for r in self.readers:
            r.start()

    @staticmethod
    def _read(stream, into):
        for line in stream:
            into.append(line)

    def err_so_far(self):
        return "".join(list(self.lines["err"]))

    def wait_for(self, condition, timeout, what):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if condition():
                return
            if self.rt is not None and self.rt.poll() is not None and self.rt.returncode != -signal.SIGKILL:
                break
            time.sleep(0.01)
        self.finish()
        fail(f"{self.name}: {what}: not within {timeout} s\n{self.out}\n{self.err}\n{self.drive.history}")

    def finish(self, timeout=60):
        self.out, self.err = "", ""
        if self.rt is not None:
            try:
                self.rt.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.rt.kill()
                self.rt.wait()
            for r in self.readers:
                r.join()
            self.out, self.err = "".join(self.lines["out"]), "".join(self.lines["err"])
        self.drive.close()
        self.network.disconnect()
        self.server.send_signal(signal.SIGTERM)
        self.server.communicate(timeout=10)
        os.unlink(self.config)
        try:
            os.unlink(f"/dev/shm/saw-can.{self.bus}")
        except FileNotFoundError:
            pass
        return self.rt.returncode if self.rt is not None else None

    def expect(self, condition, what):
        if not condition:
            fail(f"{self.name}: {what}\n--- saw-rt stdout\n{self.out}\n--- saw-rt stderr\n{self.err}\n"
                 f"--- drive\n{self.drive.history}")


def enabled(case):
    return case.drive.state == "operation enabled"


def kill9():
    c = Case("kill9", default_master=True)
    c.start()
    c.wait_for(lambda: enabled(c), 20, "the drive enabled by saw-rt")
    time.sleep(1)  # the master's heartbeats (every 100 ms by default) arm the drive's consumer
    watched, option = dict(c.drive.watched), c.drive._get(0x6007)
    c.rt.send_signal(signal.SIGKILL)
    killed = time.monotonic()
    c.rt.wait()
    c.wait_for(lambda: not enabled(c), 10, "the drive stopped by itself after saw-rt was killed")
    c.finish()
    c.expect(watched == {0x7F: 0.3}, f"0x1016 as the master wrote it: {watched} (node 127, 300 ms expected)")
    c.expect(option == 3, f"0x6007 is {option}, quick stop (3) expected")
    c.expect(c.drive.consumer_events, "the drive's heartbeat consumer did not fire")
    c.expect(c.drive.state == "quick stop active", f"the drive is {c.drive.state}")
    after = c.drive.consumer_events[0][1] - killed
    print(f"ok kill9: the drive's consumer fired {after * 1000:.0f} ms after SIGKILL; the drive quick-stopped")


def boot_fault():
    # With a deployment-level SDO write (the interpolation period, 10 ms as the task's).
    c = Case("boot_fault", extra='      sdo: ["0x60C2:01:u8=10", "0x60C2:02:i8=-3"]\n', boot_fault=0x2310)
    c.start(duration=4)
    c.wait_for(lambda: enabled(c), 20, "the drive reset and enabled")
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    c.expect((c.drive._get(0x60C2, 1), c.drive._get(0x60C2, 2)) == (10, -3), "0x60C2 not written")
    c.expect(c.drive.fault_resets >= 1, "no fault reset edge")
    c.expect(re.search(r"^\s*axis: ENABLED", c.out, re.M), "the drive did not end ENABLED")
    print(f"ok boot_fault: {c.drive.fault_resets} fault reset edge(s), then enabled")


def stuck_fault():
    c = Case("stuck_fault", boot_fault=0x2310, reset_clears=False)
    c.start(duration=5)
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    c.expect(re.search(r"^\s*axis: FAULT", c.out, re.M), "the drive did not end in FAULT")
    c.expect(re.search(r"node 5.*stays in fault.*0x2310", c.err), "no FAULT line naming node 5 and 0x2310")
    c.expect(re.search(r"continuous over-current", c.out + c.err), "the error code's name is not said")
    c.expect(1 <= c.drive.fault_resets <= 3, f"{c.drive.fault_resets} fault resets (1..3 expected)")
    c.expect("ENABLED" not in c.out.split("axis:")[1].split("\n")[0], "reported ENABLED")
    print(f"ok stuck_fault: {c.drive.fault_resets} fault resets, then FAULT naming node 5 and 0x2310")


def stuck_enable():
    c = Case("stuck_enable", stuck_in="switched on")
    c.start(duration=5)
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    c.expect(re.search(r"^\s*axis: FAULT", c.out, re.M), "the drive did not end in FAULT")
    c.expect(re.search(r"node 5.*stuck in switched on", c.err), "no FAULT line naming the state")
    print("ok stuck_enable: FAULT naming node 5 stuck in switched on")


def wrong_mode():
    c = Case("wrong_mode", mode_follows=False)
    c.start(duration=5)
    c.finish()
    c.expect(re.search(r"^\s*axis: FAULT", c.out, re.M), "the drive did not end in FAULT")
    c.expect(re.search(r"node 5.*0x6061.*mode 0.*0x6060.*mode 8", c.err), "no FAULT line naming both modes")
    c.expect(not c.drive.enabled_with_mode, f"enabled in mode {c.drive.enabled_with_mode}")
    print("ok wrong_mode: never enabled; FAULT naming 0x6061 (0) and 0x6060 (8)")


def pre_op():
    c = Case("pre_op")
    c.start(duration=6)
    c.wait_for(lambda: enabled(c), 20, "the drive enabled")
    c.drive.leave_operational()
    c.finish()
    c.expect(re.search(r"^\s*axis: FAULT", c.out, re.M), "the drive did not end in FAULT")
    c.expect(re.search(r"node 5.*left operational.*pre-operational", c.err), "no FAULT line naming the state")
    c.expect(re.search(r"NMT state", c.out), "the summary does not say the NMT state")
    print("ok pre_op: FAULT at the heartbeat saying pre-operational")


def warning():
    c = Case("warning")
    c.start(duration=5)
    c.wait_for(lambda: enabled(c), 20, "the drive enabled")
    time.sleep(0.3)
    c.drive.warn(0x4210, 0x09)
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    c.expect(re.search(r"^\s*axis: ENABLED", c.out, re.M), "a warning faulted the drive")
    c.expect(re.search(r"warning.*node 5.*0x4210.*temperature", c.err), "no warning line in hex with its name")
    c.expect(re.search(r"1 warning.*0x4210", c.out), "the status does not show the warning")
    c.expect("FAULT" not in c.err, "a FAULT was logged")
    print("ok warning: EMCY 0x4210 logged and shown, the drive stayed enabled")


def error_emcy():
    c = Case("error_emcy")
    c.start(duration=5)
    c.wait_for(lambda: enabled(c), 20, "the drive enabled")
    time.sleep(0.3)
    c.drive.fault(0x2310, 0x03)
    c.finish()
    c.expect(re.search(r"^\s*axis: FAULT", c.out, re.M), "the drive did not end in FAULT")
    c.expect(re.search(r"node 5.*EMCY 0x2310.*continuous over-current", c.err), "no FAULT line with the code")
    print("ok error_emcy: FAULT naming EMCY 0x2310 (continuous over-current)")


def rpdo_deadline():
    c = Case("rpdo_deadline", deadline="500ms")  # the consumer: 3 s
    c.start(duration=8)
    c.wait_for(lambda: enabled(c), 20, "the drive enabled")
    time.sleep(0.5)
    deadlines = dict(c.drive.rpdo_deadlines)
    c.rt.send_signal(signal.SIGSTOP)  # a starved master: nothing leaves it
    stopped = time.monotonic()
    c.wait_for(lambda: c.drive.rpdo_timeouts, 2.5, "the drive's RPDO deadline fired")
    fired = c.drive.rpdo_timeouts[0][1] - stopped
    c.rt.send_signal(signal.SIGCONT)
    c.wait_for(lambda: "RPDO timeout" in c.err_so_far(), 20, "saw-rt seeing the drive's EMCY 0x8250")
    c.finish()
    c.expect(deadlines and set(deadlines.values()) == {0.5}, f"the RPDOs' event timers: {deadlines}")
    c.expect(not c.drive.consumer_events, "the heartbeat consumer fired: the stop outlasted 3 s")
    # Its state then (saw-rt's exit later disables it, as always).
    after = [what for t, what in c.drive.history if t >= stopped and what.startswith("state ")]
    c.expect(after[:1] == ["state quick stop active"], f"the drive after the deadline: {after}")
    # Both ends saw the stop: the drive (its EMCY 0x8250, logged by saw-rt), and saw-rt's own loop,
    # whose deadline policy faults the axis at its first wake-up after a stop of 50 periods or more.
    # Which cause stands is whichever saw-rt read first (the stop is ~50 of its 10 ms periods).
    c.expect(re.search(r"node 5.*0x8250 \(RPDO timeout\)", c.err), "no line naming the drive's EMCY 0x8250")
    cause = re.search(r"axis: FAULT.*(deadline missed: \d+ periods in a row|emergency message.*0x8250)", c.err)
    c.expect(cause, "no FAULT of the axis naming the drive's EMCY 0x8250 or its own missed deadline")
    print(f"ok rpdo_deadline: the drive's RPDO deadline fired {fired * 1000:.0f} ms after SIGSTOP (500 ms written); "
          f"it quick-stopped; saw-rt logged its EMCY 0x8250 and faulted: {cause.group(1) if cause else '?'}")


def identity():
    c = Case("identity", extra=f"      eds: {EDS}\n", vendor=0x1234)
    c.start()
    code = c.finish()
    lines = [line for line in c.err.splitlines() if line.strip()]
    c.expect(code == 1, f"saw-rt exited {code}")
    c.expect(re.search(r"node 5.*vendor-ID \(0x1018:01\) 0x00001234, but .*sim_drive.eds says 0x000005A7", c.err),
             "the mismatch is not named")
    c.expect(len(lines) == 1, f"{len(lines)} lines on stderr")
    # The same drive with the EDS's identity starts.
    c = Case("identity_ok", extra=f"      eds: {EDS}\n")
    c.start(duration=3)
    c.wait_for(lambda: enabled(c), 20, "the drive whose identity is the EDS's enabled")
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    print("ok identity: start-up refused naming both vendor-IDs; the right drive starts")


def configuration(drive):
    """What the master configures, as the drive holds it: PDOs (identifier, entries), 0x1017,
    0x1016:01, 0x6007, 0x6060."""
    pdos = [drive._mapping(base + n, base + 0x200 + n) for base in (0x1400, 0x1800) for n in range(4)]
    return {"pdos": pdos, "0x1017": drive._get(0x1017), "0x1016:01": drive._get(0x1016, 1),
            "0x6007": drive._get(0x6007), "0x6060": drive._get(0x6060)}


def reboot():
    # The deployment's gateway on loopback (a DDS domain no other test holds), as a lab runs it.
    from child_tools import dds_domain
    domain = str(dds_domain())
    top = f"exports:\n  - {{component: axis, provided: drive}}\ngateway:\n  domain: {domain}\n"
    c = Case("reboot", extra="      max_velocity: 10\n", top=top)

    def ctl(*args):
        p = subprocess.run([SAWCTL, *args, "--domain", domain, "--timeout", "20"], capture_output=True, text=True,
                           timeout=60)
        return p.returncode, (p.stdout + p.stderr).strip()

    c.start()
    # The component's enable done (a reboot during an enable is the enable's to configure again).
    c.wait_for(lambda: re.search(r"\bENABLED\b(?! busy)", ctl("echo", "rt/axis/operating_state", "-n", "1")[1]),
               60, "saw-rt says the drive ENABLED (sawctl)")
    c.expect(enabled(c), f"saw-rt says ENABLED, the drive is {c.drive.state}")
    configured = configuration(c.drive)
    c.drive.reboot()
    rebooted = time.monotonic()
    defaults = configuration(c.drive)
    c.wait_for(lambda: "rebooted (boot-up seen)" in c.err_so_far(), 20, "saw-rt's FAULT naming the reboot")
    state_rc, state = ctl("echo", "rt/axis/operating_state", "-n", "1")
    enable_rc, enable = ctl("call", "rt/axis/state_command", "enable")
    delivered = time.monotonic()
    c.wait_for(lambda: enabled(c) and c.drive.node.nmt.state == "OPERATIONAL", 30,
               "the drive configured again and enabled after the sawctl enable")
    enabled_at = time.monotonic()
    again = configuration(c.drive)
    written = {(index, sub) for t, index, sub in c.drive.writes if t > rebooted}
    # A target of this run's own (0.25 rad: 163 counts at 4096 per revolution), through the gateway.
    jp_rc, jp = ctl("call", "rt/axis/servo_jp", "0.25")
    c.wait_for(lambda: any(t > enabled_at and v == 163 for t, v in c.drive.targets), 30,
               "the servo_jp target in the drive's 0x607A")
    c.rt.send_signal(signal.SIGTERM)
    code = c.finish()
    c.expect(code == 0, f"saw-rt exited {code}")
    c.expect(defaults != configured and defaults["0x1016:01"] == 0 and defaults["0x6007"] == 1
             and defaults["0x1017"] == 0, f"the reboot did not bring back the EDS's defaults: {defaults}")
    c.expect(re.search(r"axis: FAULT.*node rebooted", c.err), "no FAULT line naming the reboot")
    c.expect(re.search(r"j \(node 5\) rebooted \(boot-up seen\)", c.err), "the reboot line does not name node 5")
    c.expect(state_rc == 0 and "FAULT" in state, f"sawctl echo of the operating state: {state}")
    c.expect(enable_rc == 0 and "delivered" in enable, f"sawctl call enable: {enable}")
    c.expect(re.search(r"j \(node 5\) configured again after its reboot", c.err), "no line saying it was configured")
    c.expect(re.search(r"axis: ENABLED", c.out), "the drive did not end ENABLED")
    c.expect(re.search(r"1 faults; the last: node rebooted .* on j \(node 5\)", c.out),
             "the summary does not say the last fault was the reboot")
    c.expect(again == configured, f"the drive's configuration after the enable {again}, before the reboot {configured}")
    for obj in [(0x1017, 0), (0x1016, 1), (0x6007, 0), (0x6060, 0), (0x1400, 1), (0x1600, 0), (0x1800, 1),
                (0x1A00, 0)]:
        c.expect(obj in written, f"0x{obj[0]:04X}:{obj[1]:02X} not written again after the reboot: {sorted(written)}")
    c.expect(jp_rc == 0 and "delivered" in jp, f"sawctl call servo_jp: {jp}")
    print(f"ok reboot: FAULT naming the reboot; after the sawctl enable the drive was configured again "
          f"({len(written)} objects written), operational, operation enabled, and took a servo_jp target")
    print(f"figure: operation enabled {1000 * (enabled_at - delivered):.0f} ms after sawctl's enable returned "
          f"({len(written)} objects written by SDO, NMT start, the 402 walk-up; a 10 ms period)")


CASES = [kill9, boot_fault, stuck_fault, stuck_enable, wrong_mode, pre_op, warning, error_emcy, rpdo_deadline,
         identity, reboot]

if __name__ == "__main__":
    wanted = sys.argv[5:]
    for case in CASES:
        if not wanted or case.__name__ in wanted:
            case()
