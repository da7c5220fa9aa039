"""sawctl against a real saw-rt whose deployment starts its gateway (a `gateway:` section): list
shows the component, echo prints its state, call sends valid commands (delivered, and they run)
and refuses invalid ones before sending. The operating state is latched: an echo started after
the last change prints it. A gateway killed with -9 is told from a quiet one (echo exits 3, "gone",
after the 1 s participant lease), and a killed RT process is seen as FAULT (its gateway says so
before it leaves).

usage: sawctl_test.py SAW_RT SAW_GATEWAY SAWCTL
"""
import os
import queue
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from harness import check, dds_domain, exit_code  # noqa: E402


def main(saw_rt, saw_gateway, sawctl):
    name = f"ctl{os.getpid()}"
    domain = str(dds_domain())
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(deployment(name, domain))
    rt = subprocess.Popen([saw_rt, f.name], stdout=subprocess.PIPE, text=True)

    def ctl(*args):
        p = subprocess.run([sawctl, *args, "--domain", domain, "--timeout", "10"], capture_output=True, text=True,
                           timeout=60)
        return p.returncode, p.stdout + p.stderr

    def ctl_env(env, *args, timeout="3"):
        p = subprocess.run([sawctl, *args, "--domain", domain, "--timeout", timeout], capture_output=True,
                           text=True, timeout=60, env=dict(os.environ, **env))
        return p.returncode, p.stdout + p.stderr

    def ctl_background(*args):
        return subprocess.Popen([sawctl, *args, "--domain", domain, "--timeout", "30"], stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True)

    try:
        rc, out = ctl("list")
        check(rc == 0 and f"{name}.measured_cp" in out and f"rt/{name}/servo_cf" in out,
              "sawctl list shows the component's commands and topics")
        # ROS 2's ROS_AUTOMATIC_DISCOVERY_RANGE (OFF and LOCALHOST across a subnet: routed_peers.py).
        rc, out = ctl_env({"ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}, "list", timeout="10")
        check(rc == 0 and f"{name}.measured_cp" in out, "ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST: found")
        rc, out = ctl_env({"ROS_AUTOMATIC_DISCOVERY_RANGE": "NEARBY"}, "list")
        check(rc != 0 and len(out.strip().splitlines()) == 1 and "ROS_AUTOMATIC_DISCOVERY_RANGE=NEARBY" in out,
              f"an unknown range is one line naming it: {out.strip()}")
        rc, out = ctl("echo", f"rt/{name}/measured_cp", "-n", "3")
        lines = [l for l in out.splitlines() if l.startswith("p [")]
        check(rc == 0 and len(lines) == 3, f"sawctl echo prints 3 poses: {lines}")
        rc, out = ctl("call", f"rt/{name}/state_command", "explode")
        check(rc == 2 and "unknown state command" in out, f"an invalid command is refused before sending: {out.strip()}")
        rc, out = ctl("call", f"rt/{name}/servo_cf", "0", "0", "nan")
        check(rc == 2 and "not finite" in out, f"a NaN force is refused before sending: {out.strip()}")
        rc, out = ctl("call", f"rt/{name}/servo_cf", "0", "0", "0.1")
        check(rc == 0 and "delivered" in out, f"a valid force is delivered: {out.strip()}")
        rc, out = ctl("call", f"rt/{name}/state_command", "disable")
        check(rc == 0 and "delivered" in out, f"a state command is delivered: {out.strip()}")
        rc, out = ctl("echo", f"rt/{name}/operating_state")
        check(rc == 0 and "DISABLED" in out, f"an echo started after the change prints the latched state: {out.strip()}")
        # kill -9 of the gateway while the 1 kHz deployment runs: the RT process runs on, and a
        # running echo says the gateway is gone.
        echo = ctl_background("echo", f"rt/{name}/measured_cp", "-n", "100000000")
        lines = Lines(echo)
        check(lines.wait_for("p [", 10) is not None, "a long echo prints poses")
        gws = subprocess.run(["pgrep", "-P", str(rt.pid), "saw-gateway"], capture_output=True, text=True).stdout.split()
        check(len(gws) == 1, f"the deployment started one gateway: {gws}")
        killed = time.monotonic()
        for g in gws:
            os.kill(int(g), signal.SIGKILL)
        gone = lines.wait_for("is gone", 10)
        echo.wait(timeout=5)
        check(gone is not None and echo.returncode == 3, f"the echo says the killed gateway is gone: {gone}")
        if gone is not None:
            print(f"figure: the killed gateway seen gone after {gone - killed:.2f} s (participant lease 1 s)")
        try:
            rt.wait(timeout=1.0)  # a bound: the RT process must still be running after it
        except subprocess.TimeoutExpired:
            pass
        check(rt.poll() is None, "the RT process survives its gateway's kill -9")
    finally:
        rt.send_signal(signal.SIGTERM)  # stops its gateway too
        out, _ = rt.communicate(timeout=20)
        os.unlink(f.name)
        print(out)
        m = re.search(rf"\n\s+{name}\s+1\.00ms\s+(\d+)\s+(\d+)\s+(\d+)", out)
        check(rt.returncode == 0 and m is not None, "saw-rt ended normally and printed its task summary")
        if m:
            print(f"figure: {m.group(2)} overruns in {m.group(1)} cycles, the gateway killed with -9 meanwhile")
    rt_killed(saw_rt, sawctl, f"{name}k", domain)
    teleop_settings(saw_rt, sawctl, domain)
    return exit_code()


def teleop_settings(saw_rt, sawctl, domain):
    """The teleoperation's settings over DDS: their bounds are in the registry, sawctl refuses a
    value outside them (or its type's range) before sending, a valid one is delivered, and each
    setting's read-back shows the value in force."""
    config = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "config", "teleop-sim.yaml")
    tele = f"teleop{os.getpid()}"  # its own shared-memory segment, beside other tests' deployments
    with open(config) as src, tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        text = src.read().replace("name: teleop-sim", f"name: teleop-sim-{os.getpid()}", 1)
        for key in ("name: teleop\n", "client: teleop,", "teleop."):
            text = text.replace(key, key.replace("teleop", tele))
        f.write(text)
        f.write(f"exports:\n  - {{component: {tele}, provided: teleop}}\ngateway:\n  domain: {domain}\n")
    rt = subprocess.Popen([saw_rt, f.name, "--duration", "30"], stdout=subprocess.DEVNULL)

    def ctl(*args):
        p = subprocess.run([sawctl, *args, "--domain", domain, "--timeout", "10"], capture_output=True, text=True,
                           timeout=60)
        return p.returncode, p.stdout + p.stderr
    try:
        rc, out = ctl("list")
        gains = [line for line in out.splitlines() if f"{tele}.set_gains" in line]
        check(rc == 0 and len(gains) == 1 and "in [0, 10000]" in gains[0],
              f"the registry carries set_gains and its bounds: {gains}")
        rc, out = ctl("call", f"rt/{tele}/set_gains", "1e6", "100")
        check(rc == 2 and "outside [0, 10000]" in out, f"a gain out of bounds is refused before sending: {out.strip()}")
        rc, out = ctl("call", f"rt/{tele}/set_gains", "250", "250")
        check(rc == 0 and "delivered" in out, f"valid gains are delivered: {out.strip()}")
        rc, out = ctl("call", f"rt/{tele}/set_force_limits", "2", "2.5")
        check(rc == 0 and "delivered" in out, f"valid force limits are delivered: {out.strip()}")
        rc, out = ctl("call", f"rt/{tele}/set_scale", "0.5")
        check(rc == 0 and "delivered" in out, f"a scale is delivered: {out.strip()}")
        # The collaborative law's offset limits and prediction: read back, set, refused out of range.
        rc, out = ctl("echo", f"rt/{tele}/offset_limits")
        check(rc == 0 and "0.05 0.5 10" in out, f"the offset limits in force are read back: {out.strip()}")
        set_refused_and_read_back(ctl, f"rt/{tele}", "offset_limits", ("50", "0.5", "10"),
                                  "an offset velocity above 10 m/s", ("0.1", "1", "20"))
        set_refused_and_read_back(ctl, f"rt/{tele}", "prediction", ("1", "2", "0"),
                                  "a prediction horizon above 1 s", ("1", "0.02", "0.01"))
    finally:
        rt.terminate()
        rt.wait(timeout=20)
        os.unlink(f.name)


def set_refused_and_read_back(ctl, prefix, setting, beyond, beyond_what, valid):
    """`sawctl call PREFIX/set_SETTING`: `beyond` (outside its type's range) refused before
    sending; `valid` delivered, and then read back on PREFIX/SETTING."""
    rc, out = ctl("call", f"{prefix}/set_{setting}", *beyond)
    check(rc == 2 and "outside its type's range" in out, f"{beyond_what} is refused before sending: {out.strip()}")
    rc, out = ctl("call", f"{prefix}/set_{setting}", *valid)
    check(rc == 0 and "delivered" in out, f"set_{setting} {' '.join(valid)} is delivered: {out.strip()}")
    check(echoed(ctl, f"{prefix}/{setting}", " ".join(valid)), f"the new {setting.replace('_', ' ')} is read back")


def echoed(ctl, topic, text, attempts=10):
    """Whether `sawctl echo` of a latched read-back prints `text` within `attempts` echoes (the
    value set arrives a cycle after the command, the echo may have caught the one before)."""
    out = ""
    for _ in range(attempts):
        rc, out = ctl("echo", topic)
        if rc == 0 and text in out:
            return True
    print(f"{topic}: last echo {out.strip()!r}, expected {text!r}")
    return False


def deployment(name, domain):
    return f"""deployment:
  name: sawctl-{name}
components:
  - name: {name}
    type: sim_haptic_device
    task: {{period: 1ms, priority: 80}}
    params: {{model: omni}}
exports:
  - {{component: {name}, provided: arm}}
gateway:
  domain: {domain}
"""


class Lines:
    """A child's output lines, read by a thread as they come, each with its arrival time."""

    def __init__(self, proc):
        self.queue = queue.Queue()
        threading.Thread(target=self._read, args=(proc.stdout,), daemon=True).start()

    def _read(self, stream):
        self.all = []
        for line in stream:
            self.all.append(line.rstrip())
            self.queue.put((time.monotonic(), line))
        self.queue.put((time.monotonic(), None))

    def wait_for(self, text, timeout):
        """The time at which a line containing `text` arrived, or None (end of output or timeout)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                t, line = self.queue.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                return None
            if line is None:
                return None
            if text in line:
                return t


def rt_killed(saw_rt, sawctl, name, domain):
    """kill -9 of the RT process: its gateway (started with it, exiting with it) publishes FAULT first."""
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(deployment(name, domain))
    rt = subprocess.Popen([saw_rt, f.name], stdout=subprocess.DEVNULL)
    echo = subprocess.Popen([sawctl, "echo", f"rt/{name}/operating_state", "-n", "2", "--domain", domain,
                             "--timeout", "30"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines = Lines(echo)
    try:
        check(lines.wait_for("", 20) is not None, "the echo prints the current operating state at once (latched)")
        killed = time.monotonic()
        rt.kill()
        seen = lines.wait_for("FAULT", 10)
        check(seen is not None, f"an echo of the operating state prints FAULT when the RT process is killed: {lines.all}")
        if seen is not None:
            print(f"figure: FAULT seen {1000 * (seen - killed):.0f} ms after kill -9 of the RT process")
    finally:
        rt.kill()
        rt.wait()
        echo.kill()
        echo.wait()
        os.unlink(f.name)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
