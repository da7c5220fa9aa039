"""Runs saw-rt on a shipped deployment file for the dVRK tests: renamed for the run (the bridge's
names are host-wide) and moved to the test's DDS domain; every output line of saw-rt and its
gateway kept with its arrival time."""
import os
import re
import signal
import subprocess
import threading
import time

CONFIG_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "config")


def shipped(config, tag, domain, names):
    """The shipped file `config` with each of `names` suffixed by `tag`, on DDS domain `domain`."""
    text = open(os.path.join(CONFIG_DIR, config)).read()
    for name in names:
        text = re.sub(r"\b" + re.escape(name) + r"\b", name + tag, text)
    return text.replace("domain: 0 ", f"domain: {domain} ")


class SawRt:
    """saw-rt (and its gateway, whose output it shares) with every output line kept and timed."""

    def __init__(self, saw_rt, path, record):
        self.lines = []
        self.p = subprocess.Popen([saw_rt, path, "--record", record], stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self):
        for line in self.p.stdout:
            self.lines.append((time.monotonic(), line.rstrip()))

    def wait_line(self, needle, timeout):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for t, line in list(self.lines):
                if needle in line:
                    return t, line
            time.sleep(0.01)
        return None

    def faults_before(self, t):
        """saw-rt's FAULT lines that arrived before time t (time.monotonic())."""
        return [line for at, line in list(self.lines) if at < t and "FAULT" in line]

    def text(self):
        return "\n".join(line for _, line in self.lines)

    def stop(self, sig=signal.SIGTERM, timeout=20):
        if self.p.poll() is None:
            self.p.send_signal(sig)
        try:
            self.p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.p.kill()
            self.p.wait()
        self.reader.join(timeout=5)
        return self.p.returncode


def arm_ready(sim, timeout=30.0):
    """True once the simulated arm is ENABLED, homed and idle (what saw-rt's device waits for),
    False after `timeout` s: a bounded poll."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if sim.operating_state() == ("ENABLED", True, False):
            return True
        time.sleep(0.02)
    return False
