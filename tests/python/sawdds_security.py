"""sawdds and sawgui take an SROS2 enclave: from --enclave or ROS 2's ROS_SECURITY_* environment,
checked for its files, turned into Cyclone DDS's <Security> configuration (with the enclave's
crl.pem); with security enabled, a missing or broken enclave is refused as sawctl refuses it, in the
same words, whatever ROS_SECURITY_STRATEGY says; a Cyclone DDS without the security plugins (PyPI's
wheel) is an error that says so, never plaintext. Needs no DDS traffic.

usage: sawdds_security.py [SAWCTL]"""
import os
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "nonrt", "python"))
from sawdds import security  # noqa: E402
from sawdds.client import LOOPBACK_URI  # noqa: E402

failures = []
SAWCTL = sys.argv[1] if len(sys.argv) > 1 else None  # the C++ tool whose refusals sawdds repeats


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


def refusals(env, enclave):
    """What sawdds and sawctl say (without their names) given `enclave`, neither starting DDS."""
    py = subprocess.run([sys.executable, "-m", "sawdds", "--enclave", enclave, "list"], capture_output=True,
                        text=True, timeout=60, env=env)
    cc = subprocess.run([SAWCTL, "list", "--timeout", "1", "--enclave", enclave], capture_output=True, text=True,
                        timeout=60, env=env)
    return (py.returncode, py.stderr.strip().removeprefix("sawdds: ")), \
        (cc.returncode, cc.stderr.strip().removeprefix("sawctl: "))


def invalid_enclaves_refused_alike(env):
    """Enclaves that exist but cannot be used, made with sawctl (and, for a foreign domain, as SROS2
    makes them): sawdds refuses each as sawctl does, in its words (OpenSSL's own detail, which sawctl
    appends to some, aside)."""
    sys.path.insert(0, os.path.join(HERE, "..", "interop"))
    import sros2_keystore
    with tempfile.TemporaryDirectory() as tmp:
        ks, other = os.path.join(tmp, "ks"), os.path.join(tmp, "other")
        for k in (ks, other):
            subprocess.run([SAWCTL, "security", "init", k], check=True, capture_output=True)
        for n in ("foreign", "revoked", "wrongkey", "tampered", "good"):
            subprocess.run([SAWCTL, "security", "enroll", ks, n, "--role", "monitor"], check=True, capture_output=True)
        subprocess.run([SAWCTL, "security", "enroll", other, "foreign", "--role", "monitor"], check=True,
                       capture_output=True)
        e = lambda n: os.path.join(ks, "enclaves", n)  # noqa: E731
        for f in ("cert.pem", "key.pem"):
            shutil.copy(os.path.join(other, "enclaves", "foreign", f), os.path.join(e("foreign"), f))
        shutil.copy(os.path.join(e("good"), "key.pem"), os.path.join(e("wrongkey"), "key.pem"))
        with open(os.path.join(e("tampered"), "permissions.p7s")) as f:
            text = f.read()
        with open(os.path.join(e("tampered"), "permissions.p7s"), "w") as f:
            f.write(text.replace("<topic>rt/saw/manifest</topic>", "<topic>rt/*</topic>", 1))
        subprocess.run([SAWCTL, "security", "revoke", ks, "revoked"], check=True, capture_output=True)
        sros2 = os.path.join(tmp, "sros2")
        sros2_keystore.create_keystore(sros2, 3)
        sros2_keystore.create_enclave(sros2, "/viewer", 3)
        cases = [("another keystore's certificate", e("foreign"), "is not accepted by the enclave's identity CA"),
                 ("a revoked certificate", e("revoked"), "was revoked on"),
                 ("another certificate's key", e("wrongkey"), "key.pem is not the key of cert.pem"),
                 ("tampered permissions", e("tampered"),
                  "permissions.p7s is not signed by the enclave's permissions CA"),
                 ("a domain the governance does not cover", os.path.join(sros2, "enclaves", "viewer"),
                  "domain 0 is not in the governance's domains 3")]
        for what, enclave, want in cases:
            (rc_py, py), (rc_cc, cc) = refusals(env, enclave)
            check(rc_py == 1 and rc_cc == 1 and want in py and (cc == py or cc.startswith(py + ": error:")),
                  f"{what}: sawdds refuses as sawctl does: {py!r} / sawctl: {cc!r}")
        (rc_py, py), (rc_cc, cc) = refusals(env, e("good"))
        check("no DDS Security plugins" in py or rc_py == 0, f"a good enclave passes the checks: {py!r}")
        debian = "/usr/lib/x86_64-linux-gnu/libddsc0debian"
        if os.path.exists(os.path.join(debian, "libdds_security_auth.so")):
            r = subprocess.run([sys.executable, "-m", "sawgui", "--enclave", os.path.join(sros2, "enclaves", "viewer"),
                                "--headless", "1"], capture_output=True, text=True, timeout=60,
                               env=dict(env, SAWDDS_SECURITY_PLUGINS=debian))
            check(r.returncode == 2 and "domain 0 is not in the governance's domains 3" in r.stderr,
                  f"sawgui names the domain its enclave does not cover, before DDS starts: {r.stderr.strip()!r}")


with tempfile.TemporaryDirectory() as ks:
    enclave = os.path.join(ks, "enclaves", "gui")
    os.makedirs(enclave)
    for name in security.ENCLAVE_FILES[:-1]:
        open(os.path.join(enclave, name), "w").close()
    check(raises(lambda: security.check_enclave(enclave), f"enclave {enclave}: missing permissions.p7s"),
          "an enclave missing a file is refused, naming the file")
    open(os.path.join(enclave, "permissions.p7s"), "w").close()
    if shutil.which("openssl"):
        check(raises(lambda: security.check_enclave(enclave), "cert.pem: not a PEM certificate"),
              "with the openssl command, the files' contents are checked too")

    check(security.resolve_enclave("x/y", env={}) == os.path.abspath("x/y"), "--enclave wins")
    check(security.resolve_enclave(None, env={}) is None, "no enclave and no ROS 2 environment: no security")
    check(security.resolve_enclave(None, env={"ROS_SECURITY_ENABLE": "TRUE"}) is None,
          "ROS_SECURITY_ENABLE is enabled by exactly 'true', as rcl and the C++ programs read it")
    ros = {"ROS_SECURITY_ENABLE": "true", "ROS_SECURITY_KEYSTORE": ks, "ROS_SECURITY_ENCLAVE_OVERRIDE": "/gui"}
    check(security.resolve_enclave(None, env=ros) == enclave, "ROS_SECURITY_KEYSTORE + ENCLAVE_OVERRIDE name it")
    for strategy in ("Permissive", "Enforce", ""):
        missing = dict(ros, ROS_SECURITY_ENCLAVE_OVERRIDE="/nobody", ROS_SECURITY_STRATEGY=strategy)
        check(raises(lambda: security.resolve_enclave(None, env=missing), "does not exist"),
              f"a missing enclave is refused whatever ROS_SECURITY_STRATEGY says ({strategy or 'unset'})")
    check(raises(lambda: security.resolve_enclave(None, env={"ROS_SECURITY_ENABLE": "true"}),
                 "ROS_SECURITY_KEYSTORE is not set"), "security enabled without a keystore is an error")
    env = dict(os.environ, **ros)
    env["CYCLONEDDS_URI"] = LOOPBACK_URI
    check(raises(lambda: security.secure_environment(0, dict(env, ROS_SECURITY_ENCLAVE_OVERRIDE="/nobody")),
                 "does not exist"), "every sawdds participant starts through the same rule (secure_environment)")

    # The same environment, the same refusal, in the same words: the C++ sawctl and the Python sawdds.
    python_env = dict(os.environ, PYTHONPATH=os.path.join(HERE, "..", "..", "nonrt", "python"))
    for k in list(python_env):
        if k.startswith("ROS_SECURITY_"):
            del python_env[k]
    broken = os.path.join(ks, "enclaves", "broken")
    os.makedirs(broken)
    for name in security.ENCLAVE_FILES[:-1]:
        open(os.path.join(broken, name), "w").close()
    cases = [("security enabled, no keystore", {"ROS_SECURITY_ENABLE": "true"}, []),
             ("no enclave named", {"ROS_SECURITY_ENABLE": "true", "ROS_SECURITY_KEYSTORE": ks}, []),
             ("a missing enclave, Permissive", dict(ros, ROS_SECURITY_ENCLAVE_OVERRIDE="/nobody",
                                                    ROS_SECURITY_STRATEGY="Permissive"), []),
             ("an enclave missing a file", dict(ros, ROS_SECURITY_ENCLAVE_OVERRIDE="/broken"), []),
             ("--enclave of no directory", {}, ["--enclave", os.path.join(ks, "nowhere")])]
    for what, extra, args in cases:
        r_py = subprocess.run([sys.executable, "-m", "sawdds", *args, "list"], capture_output=True, text=True,
                              timeout=60, env=dict(python_env, **extra))
        said = r_py.stderr.strip()
        if SAWCTL:
            r_cc = subprocess.run([SAWCTL, "list", *args], capture_output=True, text=True, timeout=60,
                                  env=dict(python_env, **extra))
            cc = r_cc.stderr.strip().removeprefix("sawctl: ")
            check(r_py.returncode == 1 and r_cc.returncode == 1 and said == "sawdds: " + cc,
                  f"{what}: sawdds refuses as sawctl does, in its words: {said!r} / sawctl: {cc!r}")
        else:
            check(r_py.returncode == 1 and said.startswith("sawdds: "), f"{what}: sawdds refuses: {said!r}")
    if SAWCTL:
        invalid_enclaves_refused_alike(python_env)
    r = subprocess.run([sys.executable, "-m", "sawgui", "--headless", "1"], capture_output=True, text=True,
                       timeout=60, env=dict(python_env, **cases[2][1]))
    check(r.returncode != 0 and "does not exist; sawrt does not fall back to plaintext" in r.stderr,
          f"sawgui refuses a missing enclave too, whatever the strategy: {r.stderr.strip()!r}")

    xml = security.security_xml(enclave, "/plugins")
    check(all(f"file:{os.path.join(enclave, f)}" in xml for f in security.ENCLAVE_FILES),
          "the <Security> element names every enclave file")
    check("initFunction='init_access_control'" in xml and "/plugins/libdds_security_crypto.so" in xml,
          "... and the three plugins")
    check("<CRL>" not in xml, "an enclave without crl.pem names no CRL")
    open(os.path.join(enclave, "crl.pem"), "w").close()
    xml = security.security_xml(enclave, "/plugins")
    check(f"<CRL>file:{os.path.join(enclave, 'crl.pem')}</CRL>" in xml.split("</Authentication>")[0],
          "an enclave's crl.pem is given to Cyclone DDS's authentication, where ROS 2 has it")

    try:
        d = security.plugin_dir(env={})
        print(f"(this Cyclone DDS has security plugins in {d})")
    except security.SecurityError as e:
        check("no DDS Security plugins" in str(e) and "docs/security.md" in str(e),
              f"PyPI's wheel: joining a secure domain is refused, saying why: {e}")
    debian = "/usr/lib/x86_64-linux-gnu/libddsc0debian"
    if os.path.exists(os.path.join(debian, "libdds_security_auth.so")):
        uri = security.security_xml(enclave, debian)
        uri = LOOPBACK_URI.replace("</Domain>", uri + "</Domain>")
        check(uri.index("<Security>") < uri.index("</Domain>") and "NetworkInterface name='lo'" in uri,
              "the secure configuration keeps loopback and puts <Security> in the domain")

    r = subprocess.run([sys.executable, "-m", "sawgui", "--enclave", os.path.join(ks, "nowhere"), "--headless", "1"],
                       capture_output=True, text=True, timeout=60,
                       env=dict(os.environ, PYTHONPATH=os.path.join(HERE, "..", "..", "nonrt", "python")))
    check(r.returncode == 2 and "no such directory" in r.stderr, f"sawgui --enclave refuses a bad enclave: {r.stderr}")

sys.exit(1 if failures else 0)
