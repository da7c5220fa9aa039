"""What the soak watches: the FAULT lines the RT processes log (each matched against the faults
an injection may cause, or counted unexpected), and a process's resident memory and open files."""
import os
import re
import time

FAULT = re.compile(r"^\[\s*([0-9.]+)\]\s+error\s+(\S+):\s+(FAULT.*)$")
# A FAULT for time: a task found its own deadline missed, or an input older than its limit, or a
# CANopen drive found its RPDO deadline (EMCY 0x8250) or the master's heartbeat passed. Safe by
# design (the loop was late and stopped); on a machine whose kernel stalls its tasks for tens of
# ms (a VM, no PREEMPT_RT) they come under load, and the soak counts them apart and re-enables.
TIMING = re.compile(r"deadline missed|input stale|feedback stale|0x8250|RPDO timeout|heartbeat")
# A joint at its soft limit: after the soak enabled again an arm whose drives had coasted while
# disabled, the teleoperation runs from where it lay, and the master's motion may carry a joint to
# its limit; the arm stops there (safe). Counted apart, only once the soak has re-enabled it.
LIMIT = re.compile(r"joint limit")
# The teleoperation's FAULT that follows its device's (within 5 s, the same process: the soak may
# enable the teleoperation while its device is still in FAULT).
CONSEQUENT = re.compile(r"FAULT: (master|slave) device in FAULT")


class FaultLog:
    """Tails one saw-rt's stderr. Each new FAULT line is expected when an open expectation's
    pattern matches it (component and text), else unexpected."""

    def __init__(self, path):
        self.path, self.pos = path, 0
        self.expect = []  # (until monotonic s, component regex, text regex, injection)
        self.unexpected, self.expected, self.timing, self.limit = [], [], [], []
        self.last_line = ""  # the last FAULT (not a consequent one)
        self.last_device_fault = None  # (time, which list it went to)
        self.timing_pending = False  # a timing FAULT the soak has not yet recovered from

    def allow(self, component, text, until, injection):
        self.expect.append((until, re.compile(component), re.compile(text), injection))

    def close(self, injection, until):
        """The injection recovered: what it may cause is expected until `until` only."""
        self.expect = [(min(u, until) if inj == injection else u, c, t, inj) for u, c, t, inj in self.expect]

    def poll(self):
        try:
            with open(self.path, errors="replace") as f:
                f.seek(self.pos)
                chunk = f.read()
        except FileNotFoundError:
            return
        # Only whole lines: a line the process is still writing is read next time.
        cut = chunk.rfind("\n") + 1
        self.pos += len(chunk[:cut].encode(errors="replace"))
        # Each line is judged at its own time (saw-rt's log is CLOCK_MONOTONIC, as time.monotonic):
        # a FAULT logged within an expectation but read after it ended is still expected. The
        # expectations are kept for a minute past their end: lines are read seconds late at most.
        now = time.monotonic()
        self.expect = [e for e in self.expect if e[0] > now - 60]
        for line in chunk[:cut].splitlines():
            m = FAULT.match(line)
            if not m:
                continue
            t, comp_name, text_ = float(m.group(1)), m.group(2), m.group(3)
            follows = self.last_device_fault if CONSEQUENT.search(text_) else None
            if follows and t - follows[0] < 5.0:
                follows[1].append(line)  # with its device's FAULT
                continue
            self.last_line = line
            for until, comp, text, inj in self.expect:
                if t <= until and comp.search(comp_name) and text.search(text_):
                    self.expected.append((inj, line))
                    self.last_device_fault = (t, self.expected)
                    break
            else:
                # An arm stopped at its soft limit: the paper's law lets the slave walk while its
                # force is at the limit (its ratchet), which stress-ng makes common (10 cm in 25 s
                # seen on the first enable); the drive stops there, safe. Counted, homed, enabled.
                if LIMIT.search(text_):
                    self.limit.append(line)
                    self.timing_pending = True  # enabled again as after a late loop
                    self.last_device_fault = (t, self.limit)
                elif TIMING.search(text_):
                    self.timing.append(line)
                    self.timing_pending = True
                    self.last_device_fault = (t, self.timing)
                else:
                    self.unexpected.append(line)
                    self.last_device_fault = (t, self.unexpected)


def rss_kib(pid):
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmRSS:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return None


def fds(pid):
    try:
        return len(os.listdir(f"/proc/{pid}/fd"))
    except OSError:
        return None
