"""An independent secure DDS peer: Debian's Cyclone DDS 0.10 (C, with its DDS Security plugins),
enrolled from our keystore, against our secure saw-gateway (Fast DDS) on loopback. The enrolled
operator reads measured_cp and its servo_cf reaches the device (command_timeout turns 1); the same
program without security, and with a monitor's enclave, gets nothing through.

usage: cyclone_secure_peer.py SAW_RT SAW_GATEWAY SAWCTL SAW_CYCLONE_PEER SECURITY_PLUGIN_DIR
"""
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

from harness import check, dds_domain, exit_code  # noqa: E402

LOOPBACK = ("<General><Interfaces><NetworkInterface name='lo'/></Interfaces><AllowMulticast>false</AllowMulticast>"
            "</General><Discovery><ParticipantIndex>auto</ParticipantIndex>"
            "<MaxAutoParticipantIndex>31</MaxAutoParticipantIndex><Peers><Peer address='127.0.0.1'/></Peers>"
            "</Discovery>")


def cyclone_uri(plugins, enclave=None):
    """CYCLONEDDS_URI on loopback; with `enclave`, DDS Security with that enclave's files."""
    security = ""
    if enclave:
        f = lambda name: f"file:{os.path.join(enclave, name)}"  # noqa: E731
        lib = lambda kind, init, fin: (f"<Library path='{os.path.join(plugins, 'libdds_security_' + kind + '.so')}' "  # noqa: E731
                                       f"initFunction='{init}' finalizeFunction='{fin}'/>")
        security = ("<Security><Authentication>" + lib("auth", "init_authentication", "finalize_authentication") +
                    f"<IdentityCA>{f('identity_ca.cert.pem')}</IdentityCA>"
                    f"<IdentityCertificate>{f('cert.pem')}</IdentityCertificate>"
                    f"<PrivateKey>{f('key.pem')}</PrivateKey></Authentication>"
                    "<AccessControl>" + lib("ac", "init_access_control", "finalize_access_control") +
                    f"<PermissionsCA>{f('permissions_ca.cert.pem')}</PermissionsCA>"
                    f"<Governance>{f('governance.p7s')}</Governance>"
                    f"<Permissions>{f('permissions.p7s')}</Permissions></AccessControl>"
                    "<Cryptographic>" + lib("crypto", "init_crypto", "finalize_crypto") + "</Cryptographic></Security>")
    return f"<CycloneDDS><Domain Id='any'>{LOOPBACK}{security}</Domain></CycloneDDS>"


def main(saw_rt, saw_gateway, sawctl, peer, plugins):
    if not os.path.exists(os.path.join(plugins, "libdds_security_auth.so")):
        print(f"SKIP: no Cyclone DDS security plugins in {plugins!r}")
        return 77
    name = f"cys{os.getpid()}"
    domain = str(dds_domain())  # this test's alone
    tmp = tempfile.mkdtemp(prefix="saw-cyclone-secure-")
    ks = os.path.join(tmp, "keystore")
    enclave = lambda n: os.path.join(ks, "enclaves", n)  # noqa: E731

    def run(args, env=None, timeout=60):
        p = subprocess.run(args, capture_output=True, text=True, timeout=timeout, env=env)
        return p.returncode, (p.stdout + p.stderr).strip()

    def cyclone(*args, enclave_dir=None):
        env = dict(os.environ, CYCLONEDDS_URI=cyclone_uri(plugins, enclave_dir))
        return run([peer, *args], env=env)

    def command_timeout():
        return run([sawctl, "echo", f"rt/{name}/command_timeout", "-n", "1", "--domain", domain, "--timeout", "10",
                    "--enclave", enclave("op")])[1].splitlines()[-1:]

    run([sawctl, "security", "init", ks])
    for n, role in (("gateway", "gateway"), ("op", "operator"), ("cyclone_op", "operator"),
                    ("cyclone_mon", "monitor")):
        rc, out = run([sawctl, "security", "enroll", ks, n, "--role", role])
        check(rc == 0, f"enrolled {n}: {out}")
    yaml = os.path.join(tmp, "arm.yaml")
    with open(yaml, "w") as f:
        f.write(f"deployment: {{name: {name}}}\ncomponents:\n"
                f"  - {{name: {name}, type: sim_haptic_device, task: {{period: 1ms, priority: 80}}, "
                f"params: {{model: omni}}}}\nexports:\n  - {{component: {name}, provided: arm}}\n")
    rt = subprocess.Popen([saw_rt, yaml], stdout=subprocess.DEVNULL)
    gw = subprocess.Popen([saw_gateway, "--attach", name, "--domain", domain, "--wait", "10", "--enclave",
                           enclave("gateway")], stdout=subprocess.PIPE, text=True)
    try:
        check("endpoints" in gw.stdout.readline(), "the secure gateway started")
        rc, out = cyclone("read", domain, name, "3", "5")
        check(rc == 1 and "received 0 " in out, f"Cyclone DDS without security reads nothing: {out}")
        rc, out = cyclone("write", domain, name, "2")
        check(rc == 1, f"Cyclone DDS without security matches no command reader: {out}")
        rc, out = cyclone("write", domain, name, "2", enclave_dir=enclave("cyclone_mon"))
        check(rc == 2 and "Not Allowed By Security" in out,
              f"a Cyclone DDS monitor may not make a servo_cf writer: {out.splitlines()[-1:]}")
        seen = command_timeout()
        check(seen == ["0"], f"no command reached the device so far (command_timeout {seen})")

        t0 = time.monotonic()
        rc, out = cyclone("read", domain, name, "5", "30", enclave_dir=enclave("cyclone_op"))
        check(rc == 0, f"an enrolled Cyclone DDS operator reads measured_cp from the Fast DDS gateway: {out}")
        print(f"figure: secure Cyclone DDS peer: first pose {time.monotonic() - t0:.2f} s after start "
              f"(process start, handshake and discovery included)", flush=True)
        rc, out = cyclone("write", domain, name, "2", enclave_dir=enclave("cyclone_op"))
        check(rc == 0, f"an enrolled Cyclone DDS operator's servo_cf is matched by the gateway: {out}")
        deadline = time.monotonic() + 10
        seen = []
        while time.monotonic() < deadline and seen != ["1"]:
            seen = command_timeout()
        check(seen == ["1"], "the Cyclone DDS operator's servo_cf reached the device (command_timeout 1 after it)")
    finally:
        gw.send_signal(signal.SIGTERM)
        gw.wait(timeout=20)
        rt.send_signal(signal.SIGTERM)
        rt.wait(timeout=20)
        shutil.rmtree(tmp)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:6]))
