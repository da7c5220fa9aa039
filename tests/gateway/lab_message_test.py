"""A lab's own message type end to end, as docs/extending.md "Adding a message type" describes it
(examples/lab_message): saw-rt runs the lab's component (a plug-in) whose setting is of the lab's
type; the gateway maps it with the lab's mapping module ($SAW_MAPPING_PATH), which is one
registration line; sawctl lists it under the lab's DDS type, sends a value and echoes it back; a
value outside the component's declared bounds is refused; sawdds reads and sends it with classes
made from the lab's IDL ($SAWDDS_IDL_PATH), a Cyclone DDS peer written apart from the gateway.

usage: lab_message_test.py SAW_RT SAWCTL PLUGIN MAPPINGS_DIR IDL_DIR
"""
import os
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "support", "python"))
from saw_testing.dds_domain import dds_domain  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def deployment(name, plugin, domain):
    return f"""deployment:
  name: lab-message-{name}
plugins: [{plugin}]
components:
  - name: {name}
    type: lab_tuning
    task: {{period: 10ms}}
    params: {{stiffness: 200, max_force: 2}}
exports:
  - {{component: {name}, provided: tuning}}
gateway:
  domain: {domain}
"""


def main(saw_rt, sawctl, plugin, mappings, idl_dir):
    name = f"tuning{os.getpid()}"
    domain = str(dds_domain())
    env = dict(os.environ, SAW_MAPPING_PATH=mappings, SAWDDS_IDL_PATH=idl_dir)
    with tempfile.NamedTemporaryFile("w", suffix=".yaml", delete=False) as f:
        f.write(deployment(name, plugin, domain))
    rt = subprocess.Popen([saw_rt, f.name], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)

    def ctl(*args):
        p = subprocess.run([sawctl, *args, "--domain", domain, "--timeout", "10"], capture_output=True, text=True,
                           timeout=60, env=env)
        return p.returncode, p.stdout + p.stderr

    try:
        rc, out = ctl("list")
        line = next((l for l in out.splitlines() if f"{name}.set_spring" in l), "")
        check(rc == 0 and "lab::SpringParams" in line and f"rt/{name}/set_spring" in line,
              f"the gateway maps the lab's type with the lab's module: {line.strip()!r}")
        rc, out = ctl("echo", f"rt/{name}/spring")
        check(rc == 0 and "200 2" in out, f"sawctl echoes the deployment's value: {out.strip()}")
        rc, out = ctl("call", f"rt/{name}/set_spring", "300", "1.5")
        check(rc == 0 and "delivered" in out, f"sawctl sends the lab's type: {out.strip()}")
        deadline, out = time.monotonic() + 10, ""
        while time.monotonic() < deadline and "300 1.5" not in out:
            _, out = ctl("echo", f"rt/{name}/spring")
        check("300 1.5" in out, f"and the component's read-back says it: {out.strip()}")
        rc, out = ctl("call", f"rt/{name}/set_spring", "9000", "1")
        check(rc == 2 and "9000 is outside [0, 5000]" in out,
              f"a value outside the declared bounds is refused before sending: {out.strip()}")

        # A Cyclone DDS peer, with classes made from the lab's IDL.
        sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "nonrt", "python"))
        os.environ["SAWDDS_IDL_PATH"] = idl_dir
        from sawdds import Client, msgs
        check(msgs.SpringParams.__idl_typename__ == "lab_msgs::msg::dds_::SpringParams_",
              "sawdds makes the lab's class from its IDL under the gateway's DDS name")
        c = Client(int(domain))
        s = c.read(f"rt/{name}/spring", timeout=10)
        check((s.stiffness, s.max_force) == (300, 1.5), f"sawdds reads the lab's type: {s}")
        c.send(f"rt/{name}/set_spring", msgs.SpringParams(stiffness=450, max_force=3))
        deadline, got = time.monotonic() + 10, None
        while time.monotonic() < deadline:
            got = c.read(f"rt/{name}/spring", timeout=10)
            if got.stiffness == 450:
                break
        check(got is not None and (got.stiffness, got.max_force) == (450, 3), f"and sends it: {got}")
    finally:
        rt.terminate()
        try:
            out, _ = rt.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            rt.kill()
            out, _ = rt.communicate()
        os.unlink(f.name)
        if failures:
            print(out[-3000:])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
