"""The service manager's side of saw-rt's readiness notification ($NOTIFY_SOCKET, sd_notify's datagrams).

A test that stops saw-rt as a service manager does waits for READY=1 instead of a guessed
start-up time (under emulation the packages alone can take seconds to load).
"""

import os
import select
import socket
import tempfile
import time


class NotifySocket:
    """A datagram socket saw-rt is told about through the environment it is given."""

    def __init__(self):
        self.dir = tempfile.mkdtemp(prefix="sawnotify")
        self.path = os.path.join(self.dir, "notify")
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind(self.path)
        self.received = []

    def env(self, base=None):
        e = dict(os.environ if base is None else base)
        e["NOTIFY_SOCKET"] = self.path
        return e

    def wait(self, state, process, timeout):
        """True once `state` (e.g. "READY=1") arrived; False if `process` ended or `timeout` s passed."""
        end = time.monotonic() + timeout
        while state not in self.received:
            left = end - time.monotonic()
            if left <= 0 or process.poll() is not None:
                return state in self.received
            if select.select([self.sock], [], [], min(left, 0.1))[0]:
                self.received += self.sock.recv(4096).decode().split("\n")
        return True

    def drain(self):
        """What has arrived so far, without waiting (after the process ended)."""
        while select.select([self.sock], [], [], 0)[0]:
            self.received += self.sock.recv(4096).decode().split("\n")
        return self.received

    def close(self):
        self.sock.close()
        os.unlink(self.path)
        os.rmdir(self.dir)
