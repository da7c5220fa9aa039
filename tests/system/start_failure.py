"""saw-rt when a device does not start: exit 1, one line naming the component and why, no abort.

Two shipped deployments without their hardware: config/canopen-sim.yaml with no simulated drives
on its bus (the CANopen start-up waits for boot-ups that never come), and
config/teleop-falcon-sim.yaml switched to `transport: usb` on a machine with no Falcon. Before the
device base they ended in std::terminate (exit 134, SIGABRT, "terminate called after throwing").

Usage: start_failure.py <saw-rt> <source dir>
"""

import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support", "python"))
from saw_testing.checks import fail  # noqa: E402
from service_ready import NotifySocket  # noqa: E402

SAW_RT, SOURCE = sys.argv[1:3]


def deployment(name, edit):
    with open(os.path.join(SOURCE, "config", name)) as f:
        text = edit(f.read())
    f = tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False)
    f.write(text)
    f.close()
    return f.name


def expect_one_line(config, component, reason):
    notify = NotifySocket()
    rt = subprocess.run([SAW_RT, config, "--duration", "3"], capture_output=True, text=True, timeout=60,
                        env=notify.env())
    os.unlink(config)
    said = notify.drain()
    notify.close()
    if "READY=1" in said:
        fail("a failed start told its service manager READY=1", rt.stdout, rt.stderr)
    if rt.returncode != 1:
        fail(f"exit {rt.returncode}, not 1", rt.stdout, rt.stderr)
    lines = [l for l in rt.stderr.splitlines() if l.startswith("saw-rt:")]
    if len(lines) != 1 or not lines[0].startswith(f"saw-rt: component '{component}': "):
        fail(f"not one line naming component '{component}'", rt.stderr)
    if not re.search(reason, lines[0]):
        fail(f"the line does not say why ({reason})", lines[0])
    if "terminate called" in rt.stderr or "summary of" in rt.stdout:
        fail("an abort or a run summary", rt.stdout, rt.stderr)
    print(f"ok: {lines[0]}")


bus = f"virtual:sawstartfail{os.getpid()}"
expect_one_line(deployment("canopen-sim.yaml", lambda t: t.replace("virtual:canopen-sim", bus)), "slave",
                r"node 1 .*no boot-up")

firmware = tempfile.NamedTemporaryFile("wb", suffix=".bin", delete=False)
firmware.write(b"\0" * 64)
firmware.close()


def usb(text):
    text = text.replace("      transport: sim\n", f"      transport: usb\n      firmware: {firmware.name}\n", 1)
    return re.sub(r"\n      sim:\n(        [^\n]*\n)+", "\n", text, count=1)


expect_one_line(deployment("teleop-falcon-sim.yaml", usb), "master", r"[Ff]alcon")
os.unlink(firmware.name)
