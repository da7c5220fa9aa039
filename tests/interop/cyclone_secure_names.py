"""Cyclone DDS peers of twenty enclave names reach our secure Fast DDS gateway, in a keystore made as
SROS2 makes it (tests/interop/sros2_keystore.py: one CA without key identifiers, SROS2's governance
and default permissions), the gateway enrolled into it with `sawctl security enroll`.

Which participant starts the DDS Security handshake depends on the certificates' subjects (the
participant GUID is derived from a hash of the subject; the lower one starts). When Fast DDS 2.9
starts it, it always offers DH+MODP-2048-256 with the public key as raw big-endian octets, which
Cyclone DDS 0.10 reads as a DER INTEGER and refuses ("Failed to convert octet sequence to ASN1
integer"); when Cyclone DDS starts, it offers ECDH+prime256v1-CEUM, which both encode alike. So
a gateway enrolled without care is reached by about half of the names; `sawctl security enroll
--role gateway` gives the gateway a subject that no peer's GUID exceeds in practice.

usage: cyclone_secure_names.py SAW_RT SAW_GATEWAY SAWCTL SAW_CYCLONE_PEER SECURITY_PLUGIN_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile

from harness import check, exit_code  # noqa: E402
from cyclone_secure_peer import cyclone_uri  # noqa: E402
import sros2_keystore  # noqa: E402

NAMES = ["/viewer", "/operator", "/patient", "/talker", "/listener", "/console", "/gui", "/monitor", "/lab/console",
         "/lab/viewer", "/or1/surgeon", "/or1/assistant", "/nurse", "/recorder", "/dashboard", "/teleop_ui",
         "/camera", "/planner", "/logger", "/sawgui"]


def main(saw_rt, saw_gateway, sawctl, peer, plugins):
    if not os.path.exists(os.path.join(plugins, "libdds_security_auth.so")):
        print(f"SKIP: no Cyclone DDS security plugins in {plugins!r}")
        return 77
    name = f"cyn{os.getpid()}"
    domain = 1 + os.getpid() % 6  # this test's DDS domains: 1-6
    tmp = tempfile.mkdtemp(prefix="saw-cyclone-names-")
    ks = os.path.join(tmp, "keystore")
    sros2_keystore.create_keystore(ks, domain)
    for n in NAMES:
        sros2_keystore.create_enclave(ks, n, domain)
    r = subprocess.run([sawctl, "security", "enroll", ks, "gateway", "--role", "gateway"], capture_output=True,
                       text=True, timeout=60)
    check(r.returncode == 0, f"sawctl enrols the gateway into the SROS2-made keystore: {(r.stdout + r.stderr).strip()}")
    if r.returncode != 0:
        shutil.rmtree(tmp)
        return exit_code()
    yaml = os.path.join(tmp, "arm.yaml")
    with open(yaml, "w") as f:
        f.write(f"deployment: {{name: {name}}}\ncomponents:\n"
                f"  - {{name: {name}, type: sim_haptic_device, task: {{period: 1ms, priority: 80}}, "
                f"params: {{model: omni}}}}\nexports:\n  - {{component: {name}, provided: arm}}\n")
    rt = subprocess.Popen([saw_rt, yaml], stdout=subprocess.DEVNULL)
    gw = subprocess.Popen([saw_gateway, "--attach", name, "--domain", str(domain), "--wait", "10", "--enclave",
                           os.path.join(ks, "enclaves", "gateway")], stdout=subprocess.PIPE, text=True)
    reached = []
    try:
        check("endpoints" in gw.stdout.readline(), "the secure gateway started")
        # Started one after the other, so that a refused handshake is not hidden by another's traffic.
        for n in NAMES:
            env = dict(os.environ, CYCLONEDDS_URI=cyclone_uri(plugins, os.path.join(ks, "enclaves", n.lstrip("/"))))
            p = subprocess.run([peer, "read", str(domain), name, "3", "8"], capture_output=True, text=True,
                               timeout=60, env=env)
            out = (p.stdout + p.stderr).strip()
            why = [line for line in out.splitlines() if "handshake" in line or "received" in line][-1:]
            check(p.returncode == 0, f"Cyclone DDS peer {n} reads measured_cp from the gateway: {why}")
            if p.returncode == 0:
                reached.append(n)
        print(f"figure: {len(reached)} of {len(NAMES)} enclave names reached the gateway", flush=True)
    finally:
        gw.send_signal(signal.SIGTERM)
        gw.wait(timeout=20)
        rt.send_signal(signal.SIGTERM)
        rt.wait(timeout=20)
        shutil.rmtree(tmp)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:6]))
