"""saw-rt under a service manager: READY=1 once every task runs, an orderly stop on SIGTERM.

A Type=notify systemd unit (and every test that stops saw-rt as a service manager would) waits
for READY=1 on $NOTIFY_SOCKET rather than guessing how long start-up takes. Checks, with the
shipped simulated teleoperation (config/teleop-sim.yaml):
- READY=1 arrives while saw-rt runs (a path socket, and one in the abstract namespace);
- SIGTERM after it: exit 0, the run's summary with the teleoperation ENABLED, STOPPING=1 said;
- no READY=1 from a start that fails (tests/system/start_failure.py checks that).

Usage: service_notify_test.py <saw-rt> <source dir>
"""

import os
import signal
import socket
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support", "python"))
from saw_testing.checks import fail  # noqa: E402
from service_ready import NotifySocket  # noqa: E402

SAW_RT, SOURCE = sys.argv[1:3]
CONFIG = os.path.join(SOURCE, "config", "teleop-sim.yaml")


def run(notify, env):
    p = subprocess.Popen([SAW_RT, CONFIG], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        if not notify.wait("READY=1", p, 60):
            p.kill()
            fail("no READY=1 from a saw-rt that runs", *p.communicate())
        if p.poll() is not None:
            fail(f"saw-rt ended by itself (exit {p.returncode})", *p.communicate())
        p.send_signal(signal.SIGTERM)
        out, err = p.communicate(timeout=60)
    finally:
        if p.poll() is None:
            p.kill()
    if p.returncode != 0:
        fail(f"exit {p.returncode} on SIGTERM, not 0", out, err)
    if "summary of 'teleop-sim'" not in out or "teleop: ENABLED" not in out:
        fail("no run summary with the teleoperation ENABLED after SIGTERM", out, err)
    if "STOPPING=1" not in notify.drain():
        fail(f"no STOPPING=1 (received {notify.received})", out, err)


def run_and_close(notify):
    """run() with `notify` as $NOTIFY_SOCKET; the socket closed whatever happens."""
    try:
        run(notify, notify.env())
    finally:
        notify.close()


run_and_close(NotifySocket())
print("ok: READY=1, then SIGTERM: exit 0, summary, STOPPING=1 (path socket)")


class AbstractSocket(NotifySocket):
    def __init__(self):
        self.path = f"@sawnotify{os.getpid()}"
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind("\0" + self.path[1:])
        self.received = []

    def close(self):
        self.sock.close()


run_and_close(AbstractSocket())
print("ok: the same with a socket in the abstract namespace")
