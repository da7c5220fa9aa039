"""sawdds and sawgui take an SROS2 enclave: from --enclave or ROS 2's ROS_SECURITY_* environment,
checked for its files, turned into Cyclone DDS's <Security> configuration; a Cyclone DDS without the
security plugins (PyPI's wheel) is an error that says so, never plaintext. Needs no DDS traffic."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "nonrt", "python"))
from sawdds import security  # noqa: E402
from sawdds.client import LOOPBACK_URI  # noqa: E402

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def raises(f, text):
    try:
        f()
    except security.SecurityError as e:
        return text in str(e)
    return False


with tempfile.TemporaryDirectory() as ks:
    enclave = os.path.join(ks, "enclaves", "gui")
    os.makedirs(enclave)
    for name in security.ENCLAVE_FILES[:-1]:
        open(os.path.join(enclave, name), "w").close()
    check(raises(lambda: security.check_enclave(enclave), "has no permissions.p7s"),
          "an enclave missing a file is refused, naming the file")
    open(os.path.join(enclave, "permissions.p7s"), "w").close()
    security.check_enclave(enclave)

    check(security.resolve_enclave("x/y", env={}) == os.path.abspath("x/y"), "--enclave wins")
    check(security.resolve_enclave(None, env={}) is None, "no enclave and no ROS 2 environment: no security")
    ros = {"ROS_SECURITY_ENABLE": "true", "ROS_SECURITY_KEYSTORE": ks, "ROS_SECURITY_ENCLAVE_OVERRIDE": "/gui"}
    check(security.resolve_enclave(None, env=ros) == enclave, "ROS_SECURITY_KEYSTORE + ENCLAVE_OVERRIDE name it")
    missing = dict(ros, ROS_SECURITY_ENCLAVE_OVERRIDE="/nobody")
    check(security.resolve_enclave(None, env=missing) is None, "Permissive: a missing enclave runs without")
    enforce = dict(missing, ROS_SECURITY_STRATEGY="Enforce")
    check(security.resolve_enclave(None, env=enforce).endswith("/enclaves/nobody"),
          "Enforce: a missing enclave is kept, to be refused by check_enclave")
    check(raises(lambda: security.secure_uri(LOOPBACK_URI, security.resolve_enclave(None, env=enforce)),
                 "no such directory"), "... and refused")
    check(raises(lambda: security.resolve_enclave(None, env={"ROS_SECURITY_ENABLE": "true",
                                                             "ROS_SECURITY_STRATEGY": "Enforce"}),
                 "needs ROS_SECURITY_KEYSTORE"), "Enforce without a keystore is an error")

    xml = security.security_xml(enclave, "/plugins")
    check(all(f"file:{os.path.join(enclave, f)}" in xml for f in security.ENCLAVE_FILES),
          "the <Security> element names every enclave file")
    check("initFunction='init_access_control'" in xml and "/plugins/libdds_security_crypto.so" in xml,
          "... and the three plugins")

    try:
        d = security.plugin_dir(env={})
        print(f"(this Cyclone DDS has security plugins in {d})")
    except security.SecurityError as e:
        check("no DDS Security plugins" in str(e) and "docs/security.md" in str(e),
              f"PyPI's wheel: joining a secure domain is refused, saying why: {e}")
    debian = "/usr/lib/x86_64-linux-gnu/libddsc0debian"
    if os.path.exists(os.path.join(debian, "libdds_security_auth.so")):
        uri = security.secure_uri(LOOPBACK_URI, enclave, env={"SAWDDS_SECURITY_PLUGINS": debian})
        check(uri.index("<Security>") < uri.index("</Domain>") and "NetworkInterface name='lo'" in uri,
              "the secure configuration keeps loopback and puts <Security> in the domain")

    r = subprocess.run([sys.executable, "-m", "sawgui", "--enclave", os.path.join(ks, "nowhere"), "--headless", "1"],
                       capture_output=True, text=True, timeout=60,
                       env=dict(os.environ, PYTHONPATH=os.path.join(HERE, "..", "..", "nonrt", "python")))
    check(r.returncode == 2 and "no such directory" in r.stderr, f"sawgui --enclave refuses a bad enclave: {r.stderr}")

sys.exit(1 if failures else 0)
