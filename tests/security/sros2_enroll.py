"""`sawctl security enroll` inside a keystore made as SROS2 makes it (one CA without a subject key
identifier: tests/interop/sros2_keystore.py): the enclave is made and OpenSSL accepts it; a failed
enrolment leaves nothing behind and a failed re-enrolment leaves the old enclave as it was; a
domain outside the governance's is named by sawctl and saw-gateway before DDS is asked.

usage: sros2_enroll.py SAW_GATEWAY SAWCTL
"""
import filecmp
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "interop"))
from harness import check, exit_code  # noqa: E402
import sros2_keystore  # noqa: E402


def run(*args):
    p = subprocess.run(list(args), capture_output=True, text=True, timeout=60)
    return p.returncode, (p.stdout + p.stderr).strip()


def main(saw_gateway, sawctl):
    domain = 3  # the governance's only domain, as SROS2 writes ROS_DOMAIN_ID; no DDS participant starts here
    tmp = tempfile.mkdtemp(prefix="saw-sros2-enroll-")
    try:
        ks = os.path.join(tmp, "ks")
        sros2_keystore.create_keystore(ks, domain)
        sros2_keystore.create_enclave(ks, "/talker", domain)
        rc, out = run("openssl", "x509", "-in", os.path.join(ks, "public", "ca.cert.pem"), "-noout", "-ext",
                      "subjectKeyIdentifier")
        check("Subject Key Identifier" not in out, f"the SROS2-made CA has no subject key identifier: {out!r}")

        rc, out = run(sawctl, "security", "enroll", ks, "lab/console", "--role", "operator")
        check(rc == 0, f"sawctl enrols lab/console into the SROS2 keystore: {out}")
        console = os.path.join(ks, "enclaves", "lab", "console")
        rc, out = run("openssl", "verify", "-CAfile", os.path.join(ks, "public", "ca.cert.pem"),
                      os.path.join(console, "cert.pem"))
        check(rc == 0, f"openssl verifies its certificate against SROS2's CA: {out}")
        rc, out = run(sawctl, "security", "check", console)
        check(rc == 0, f"and it checks out as the programs check it: {out}")
        rc, out = run(sawctl, "security", "enroll", ks, "gateway", "--role", "gateway")
        check(rc == 0, f"a gateway too: {out}")
        check(sorted(os.listdir(os.path.join(ks, "enclaves"))) ==
              ["gateway", "governance.p7s", "governance.xml", "lab", "talker"],
              f"nothing else in enclaves/: {sorted(os.listdir(os.path.join(ks, 'enclaves')))}")

        # A keystore whose CA key is unreadable: the enrolment fails after its folders would have been made.
        broken = os.path.join(tmp, "broken")
        shutil.copytree(ks, broken, symlinks=True)
        with open(os.path.join(broken, "private", "ca.key.pem"), "w") as f:
            f.write("not a key\n")
        before = sorted(os.listdir(os.path.join(broken, "enclaves")))
        rc, out = run(sawctl, "security", "enroll", broken, "or2/nurse", "--role", "monitor")
        check(rc == 1 and "ca.key.pem" in out, f"the enrolment fails, saying why: {out}")
        after = sorted(os.listdir(os.path.join(broken, "enclaves")))
        check(after == before, f"... and leaves nothing behind (not even or2/): {before} -> {after}")
        old = os.path.join(tmp, "console-before")
        shutil.copytree(os.path.join(broken, "enclaves", "lab", "console"), old, symlinks=True)
        rc, out = run(sawctl, "security", "enroll", broken, "lab/console", "--role", "monitor")
        same = filecmp.dircmp(old, os.path.join(broken, "enclaves", "lab", "console"))
        check(rc == 1 and not same.diff_files and not same.left_only and not same.right_only
              and sorted(os.listdir(os.path.join(broken, "enclaves", "lab"))) == ["console"],
              f"a failed re-enrolment leaves the old enclave as it was: {out}")

        # A domain the governance does not protect, named before Fast DDS is asked.
        rc, out = run(sawctl, "echo", "rt/x/measured_cp", "-n", "1", "--domain", "7", "--timeout", "1", "--enclave",
                      console)
        want = f"domain 7 is not in the governance's domains {domain}"
        check(rc == 1 and want in out, f"sawctl names the domain: {out}")
        rc, out = run(saw_gateway, "--attach", "x", "--domain", "7", "--wait", "1", "--enclave",
                      os.path.join(ks, "enclaves", "gateway"))
        check(rc == 1 and want in out and len(out.splitlines()) == 1, f"saw-gateway names it in one line: {out}")
    finally:
        shutil.rmtree(tmp)
    return exit_code()


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
