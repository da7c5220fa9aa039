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

Then revocation (`sawctl security revoke`, crl.pem as ROS 2 reads it): a revoked peer reads nothing
from the restarted gateway even though it does not check the CRL itself; a peer configured as
sawdds configures it (<CRL>) keeps reading, and reads nothing once the gateway itself is revoked;
sawctl and saw-gateway refuse a revoked enclave.

usage: cyclone_secure_names.py SAW_RT SAW_GATEWAY SAWCTL SAW_CYCLONE_PEER SECURITY_PLUGIN_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile

from harness import check, dds_domain, exit_code  # noqa: E402  (puts the tree's sawdds on the path)
from cyclone_secure_peer import cyclone_uri  # noqa: E402
import sros2_keystore  # noqa: E402
from sawdds import security  # noqa: E402
from sawdds.client import LOOPBACK_URI  # noqa: E402  (the tools venv's python: sawdds needs cyclonedds)

NAMES = ["/viewer", "/operator", "/patient", "/talker", "/listener", "/console", "/gui", "/monitor", "/lab/console",
         "/lab/viewer", "/or1/surgeon", "/or1/assistant", "/nurse", "/recorder", "/dashboard", "/teleop_ui",
         "/camera", "/planner", "/logger", "/sawgui"]


def main(saw_rt, saw_gateway, sawctl, peer, plugins):
    if not os.path.exists(os.path.join(plugins, "libdds_security_auth.so")):
        print(f"SKIP: no Cyclone DDS security plugins in {plugins!r}")
        return 77
    name = f"cyn{os.getpid()}"
    domain = dds_domain()  # this test's alone (its keystore's governance is made for it)
    tmp = tempfile.mkdtemp(prefix="saw-cyclone-names-")
    ks = os.path.join(tmp, "keystore")
    sros2_keystore.create_keystore(ks, domain)
    for n in NAMES:
        sros2_keystore.create_enclave(ks, n, domain)
    r = subprocess.run([sawctl, "security", "enroll", ks, "gateway", "--role", "gateway"], capture_output=True,
                       text=True, timeout=60)
    check(r.returncode == 0, f"sawctl enrols the gateway into the SROS2-made keystore: {(r.stdout + r.stderr).strip()}")
    subprocess.run([sawctl, "security", "enroll", ks, "console", "--role", "monitor"], capture_output=True, timeout=60,
                   check=True)
    if r.returncode != 0:
        shutil.rmtree(tmp)
        return exit_code()
    yaml = os.path.join(tmp, "arm.yaml")
    with open(yaml, "w") as f:
        f.write(f"deployment: {{name: {name}}}\ncomponents:\n"
                f"  - {{name: {name}, type: sim_haptic_device, task: {{period: 1ms, priority: 80}}, "
                f"params: {{model: omni}}}}\nexports:\n  - {{component: {name}, provided: arm}}\n")
    rt = subprocess.Popen([saw_rt, yaml], stdout=subprocess.DEVNULL)
    gateway_args = ["--attach", name, "--domain", str(domain), "--wait", "10", "--enclave",
                    os.path.join(ks, "enclaves", "gateway")]
    gw = subprocess.Popen([saw_gateway, *gateway_args], stdout=subprocess.PIPE, text=True)

    def restart(old):
        old.send_signal(signal.SIGTERM)
        old.wait(timeout=20)
        return subprocess.Popen([saw_gateway, *gateway_args], stdout=subprocess.PIPE, text=True)

    def uri(enclave, crl):
        """CYCLONEDDS_URI for `enclave`: with its crl.pem as sawdds configures it, or without (a peer
        that does not check revocation itself)."""
        if not crl:
            return cyclone_uri(plugins, enclave)
        return security.secure_uri(LOOPBACK_URI, enclave, env={"SAWDDS_SECURITY_PLUGINS": plugins})

    def peer_read(cyclonedds_uri, timeout=20):
        """The peer's exit code and what it said of the handshake and the poses. A peer that reads
        returns as soon as it has; the timeout is for a busy machine (a load of 12 on 2 cores seen), and a
        peer expected to read nothing is given as long as one expected to read."""
        p = subprocess.run([peer, "read", str(domain), name, "3", str(timeout)], capture_output=True, text=True,
                           timeout=timeout + 60,
                           env=dict(os.environ, CYCLONEDDS_URI=cyclonedds_uri))
        out = (p.stdout + p.stderr).strip()
        if p.returncode != 0:
            print(f"  (saw-cyclone-peer said: {out[-2000:]})", flush=True)
        return p.returncode, [line for line in out.splitlines() if "handshake" in line or "received" in line]

    reached = []
    try:
        check("endpoints" in gw.stdout.readline(), "the secure gateway started")
        # Started one after the other, so that a refused handshake is not hidden by another's traffic.
        for n in NAMES:
            rc, out = peer_read(uri(os.path.join(ks, "enclaves", n.lstrip("/")), crl=False))
            check(rc == 0, f"Cyclone DDS peer {n} reads measured_cp from the gateway: {out[-1:]}")
            if rc == 0:
                reached.append(n)
        print(f"figure: {len(reached)} of {len(NAMES)} enclave names reached the gateway", flush=True)

        # Revocation: the gateway reads the keystore's crl.pem (linked into its enclave) when it starts.
        r = subprocess.run([sawctl, "security", "revoke", ks, "/viewer"], capture_output=True, text=True, timeout=60)
        check(r.returncode == 0 and os.path.islink(os.path.join(ks, "enclaves", "viewer", "crl.pem")),
              f"sawctl security revoke /viewer: {(r.stdout + r.stderr).strip()}")
        gw = restart(gw)
        check("endpoints" in gw.stdout.readline(), "the gateway started again, with the CRL")
        rc, out = peer_read(uri(os.path.join(ks, "enclaves", "viewer"), crl=False))
        check(rc == 1 and "received 0 " in " ".join(out),
              f"a revoked /viewer that ignores the CRL itself still reads nothing from the gateway: {out[-1:]}")
        rc, out = peer_read(uri(os.path.join(ks, "enclaves", "operator"), crl=True))
        check(rc == 0, f"/operator, given the CRL as sawdds gives it (<CRL>), still reads: {out[-1:]}")
        r = subprocess.run([sawctl, "echo", f"rt/{name}/measured_cp", "-n", "1", "--domain", str(domain),
                            "--timeout", "5", "--enclave", os.path.join(ks, "enclaves", "viewer")],
                           capture_output=True, text=True, timeout=60)
        check(r.returncode == 1 and "was revoked" in r.stderr,
              f"sawctl refuses the revoked enclave: {r.stderr.strip()}")

        def sawctl_reads():
            r = subprocess.run([sawctl, "echo", f"rt/{name}/measured_cp", "-n", "1", "--domain", str(domain),
                                "--timeout", "20", "--enclave", os.path.join(ks, "enclaves", "console")],
                               capture_output=True, text=True, timeout=80)
            return r.returncode, (r.stdout + r.stderr).strip()[-300:]
        rc, out = sawctl_reads()
        check(rc == 0, f"sawctl (Fast DDS, enclave /console enrolled by sawctl) reads from the gateway: {out!r}")
        # And the other way: peers given the CRL refuse a revoked gateway, Cyclone DDS (<CRL>) and Fast DDS.
        subprocess.run([sawctl, "security", "revoke", ks, "gateway"], capture_output=True, timeout=60, check=True)
        rc, out = peer_read(uri(os.path.join(ks, "enclaves", "operator"), crl=True))
        check(rc == 1 and "certificate revoked" in " ".join(out),
              f"a Cyclone DDS peer given the CRL reads nothing from a revoked gateway: {out[-1:]}")
        rc, out = sawctl_reads()
        check(rc != 0, f"nor does sawctl, whose Fast DDS participant is given the CRL: {out!r}")
        r = subprocess.run([saw_gateway, *gateway_args], capture_output=True, text=True, timeout=60)
        check(r.returncode == 1 and "was revoked" in r.stderr,
              f"saw-gateway refuses to start with its revoked enclave: {r.stderr.strip()}")
    finally:
        gw.send_signal(signal.SIGTERM)
        gw.wait(timeout=20)
        rt.send_signal(signal.SIGTERM)
        rt.wait(timeout=20)
        shutil.rmtree(tmp)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:6]))
