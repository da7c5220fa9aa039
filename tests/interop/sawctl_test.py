"""sawctl against a real saw-rt whose deployment starts its gateway (a `gateway:` section): list
shows the component, echo prints its state, call sends valid commands (delivered, and they run)
and refuses invalid ones before sending.

usage: sawctl_test.py SAW_RT SAW_GATEWAY SAWCTL
"""
import os
import re
import signal
import subprocess
import sys
import tempfile
from harness import check, exit_code  # noqa: E402


def main(saw_rt, saw_gateway, sawctl):
    name = f"ctl{os.getpid()}"
    domain = str(100 + (os.getpid() + 71) % 100)
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(f"""deployment:
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
""")
    rt = subprocess.Popen([saw_rt, f.name], stdout=subprocess.PIPE, text=True)

    def ctl(*args):
        p = subprocess.run([sawctl, *args, "--domain", domain, "--timeout", "10"], capture_output=True, text=True,
                           timeout=60)
        return p.returncode, p.stdout + p.stderr

    try:
        rc, out = ctl("list")
        check(rc == 0 and f"{name}.measured_cp" in out and f"rt/{name}/servo_cf" in out,
              "sawctl list shows the component's commands and topics")
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
        # kill -9 of the gateway while the 1 kHz deployment runs: the RT process runs on.
        gws = subprocess.run(["pgrep", "-P", str(rt.pid), "saw-gateway"], capture_output=True, text=True).stdout.split()
        check(len(gws) == 1, f"the deployment started one gateway: {gws}")
        for g in gws:
            os.kill(int(g), signal.SIGKILL)
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
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:4]))
