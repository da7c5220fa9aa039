"""What the CAN system tests share: failing with a message, reading a child's line with a
deadline, starting saw-socketcand on a free port of 127.0.0.1, and a DDS domain of the test's own
(fail, check and dds_domain are tests/support/python's saw_testing, re-exported here)."""

import os
import re
import selectors
import subprocess
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support", "python"))
from saw_testing.checks import check, fail  # noqa: E402, F401
from saw_testing.dds_domain import dds_domain  # noqa: E402, F401


def read_line(stream, timeout, what):
    """One line from a child's pipe, or fail after `timeout` seconds."""
    sel = selectors.DefaultSelector()
    sel.register(stream, selectors.EVENT_READ)
    if not sel.select(timeout):
        fail(f"no {what} within {timeout} s")
    return stream.readline().decode().strip()


def start_socketcand(server, bus, *extra):
    """saw-socketcand serving `bus` on a port the kernel picks; returns (process, port)."""
    process = subprocess.Popen([server, "--bus", bus, "--port", "0", *extra], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE)
    line = read_line(process.stdout, 10, "'listening on' line from saw-socketcand")
    match = re.match(r"saw-socketcand: listening on 127\.0\.0\.1:(\d+)$", line)
    check(match is not None, f"saw-socketcand said {line!r}")
    return process, int(match.group(1))
