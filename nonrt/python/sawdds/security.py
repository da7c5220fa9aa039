"""DDS Security for sawdds and sawgui: an SROS2 enclave (made by `sawctl security enroll`) as Cyclone
DDS's <Security> configuration.

An enclave is named with --enclave DIR, or by ROS 2's environment (ROS_SECURITY_ENABLE=true,
ROS_SECURITY_KEYSTORE, ROS_SECURITY_ENCLAVE_OVERRIDE). The rule is the C++ programs' (saw-gateway,
sawctl; nonrt/security/src/enclave.cpp), with their words: with security enabled, a missing or
broken enclave is an error whatever ROS_SECURITY_STRATEGY says, never plaintext. Nothing here does
cryptography: Cyclone DDS's own plugins do, and they must belong to the libddsc this Python loads.
PyPI's cyclonedds wheel has none; then joining a secure domain is an error that says so.
"""
import glob
import os
import re

from . import enclave_check

# In the order the C++ check looks for them, so that the first missing one is named alike.
ENCLAVE_FILES = ("identity_ca.cert.pem", "cert.pem", "key.pem", "permissions_ca.cert.pem", "governance.p7s",
                 "permissions.p7s")


class SecurityError(RuntimeError):
    """An enclave that cannot be used, or a Cyclone DDS that cannot do security."""


def resolve_enclave(enclave=None, env=None):
    """The enclave directory to use: `enclave` if given, else the one ROS 2's environment names,
    else None (no security: ROS_SECURITY_ENABLE is not exactly "true", as rcl reads it). Raises
    SecurityError when ROS 2's environment enables security but does not name an existing enclave."""
    env = os.environ if env is None else env
    if enclave:
        return os.path.abspath(enclave)
    if env.get("ROS_SECURITY_ENABLE", "") != "true":
        return None
    keystore = env.get("ROS_SECURITY_KEYSTORE", "")
    name = env.get("ROS_SECURITY_ENCLAVE_OVERRIDE", "")
    if not keystore:
        raise SecurityError("ROS_SECURITY_ENABLE=true but ROS_SECURITY_KEYSTORE is not set (no plaintext fallback)")
    if not name:
        raise SecurityError("ROS_SECURITY_ENABLE=true but ROS_SECURITY_ENCLAVE_OVERRIDE is not set: name this "
                            "program's enclave (e.g. /gateway) or pass --enclave (no plaintext fallback)")
    path = os.path.join(keystore, "enclaves", name.lstrip("/"))
    if not os.path.isdir(path):
        raise SecurityError(f"enclave {path} (from ROS_SECURITY_KEYSTORE and ROS_SECURITY_ENCLAVE_OVERRIDE) does "
                            "not exist; sawrt does not fall back to plaintext whatever ROS_SECURITY_STRATEGY says")
    return path


def check_enclave(path, domain=None):
    """Raises SecurityError "enclave DIR: ..." as the C++ programs say it when DIR is not a
    directory, lacks one of an SROS2 enclave's six files (the first missing one named), has a
    certificate that is expired, not yet valid, not the identity CA's, revoked by its crl.pem, or
    not its key's, documents not signed by its permissions CA (these with the `openssl` command,
    sawdds.enclave_check), or, given `domain`, does not cover that domain."""
    if not os.path.isdir(path):
        raise SecurityError(f"enclave {path}: no such directory")
    for f in ENCLAVE_FILES:
        if not os.path.isfile(os.path.join(path, f)):
            raise SecurityError(f"enclave {path}: missing {f}")
    try:
        enclave_check.check_certificates(path)
    except enclave_check.EnclaveError as e:
        raise SecurityError(f"enclave {path}: {e}") from None
    if domain is not None:
        try:
            enclave_check.check_domain(path, domain)
        except enclave_check.EnclaveError as e:  # named as its absolute path, as saw::security::check_domain does
            raise SecurityError(f"enclave {os.path.abspath(path)}: {e}") from None


def plugin_dir(env=None):
    """The directory of the DDS Security plugins built for the libddsc that cyclonedds loads:
    SAWDDS_SECURITY_PLUGINS, or beside that libddsc. SecurityError if there are none."""
    env = os.environ if env is None else env
    if env.get("SAWDDS_SECURITY_PLUGINS"):
        candidates = [env["SAWDDS_SECURITY_PLUGINS"]]
    else:
        import cyclonedds
        here = os.path.dirname(os.path.abspath(cyclonedds.__file__))
        candidates = [os.path.join(os.path.dirname(here), "cyclonedds.libs"), here]
        home = env.get("CYCLONEDDS_HOME")
        if home:
            candidates += [os.path.join(home, "lib"), os.path.join(home, "lib64")]
    for d in candidates:
        if glob.glob(os.path.join(d, "*dds_security_auth*")):
            return d
    raise SecurityError("this Cyclone DDS has no DDS Security plugins (looked in " + ", ".join(candidates) +
                        "): PyPI's cyclonedds wheel carries none. Install cyclonedds against a Cyclone DDS built "
                        "with security (CYCLONEDDS_HOME), or set SAWDDS_SECURITY_PLUGINS to its plugin "
                        "directory; see docs/security.md")


def _library(directory, name, kind):
    matches = sorted(glob.glob(os.path.join(directory, f"*dds_security_{name}*")))
    path = matches[0] if matches else os.path.join(directory, f"libdds_security_{name}.so")
    return f"<Library path='{path}' initFunction='init_{kind}' finalizeFunction='finalize_{kind}'/>"


def security_xml(enclave, plugins):
    """Cyclone DDS's <Security> element for `enclave` with the plugins in directory `plugins`."""
    def uri(name):
        return "file:" + os.path.join(enclave, name)
    # The enclave's revocation list, where ROS 2 reads it: a revoked peer is not authenticated.
    crl = f"<CRL>{uri('crl.pem')}</CRL>" if os.path.isfile(os.path.join(enclave, "crl.pem")) else ""
    return ("<Security><Authentication>" + _library(plugins, "auth", "authentication") +
            f"<IdentityCA>{uri('identity_ca.cert.pem')}</IdentityCA>"
            f"<IdentityCertificate>{uri('cert.pem')}</IdentityCertificate>"
            f"<PrivateKey>{uri('key.pem')}</PrivateKey>" + crl + "</Authentication>"
            "<AccessControl>" + _library(plugins, "ac", "access_control") +
            f"<PermissionsCA>{uri('permissions_ca.cert.pem')}</PermissionsCA>"
            f"<Governance>{uri('governance.p7s')}</Governance>"
            f"<Permissions>{uri('permissions.p7s')}</Permissions></AccessControl>"
            "<Cryptographic>" + _library(plugins, "crypto", "crypto") + "</Cryptographic></Security>")


def secure_uri(uri, enclave, env=None):
    """`uri` (a CYCLONEDDS_URI with one <Domain>) with DDS Security from `enclave` added.
    Raises SecurityError when the enclave or this Cyclone DDS cannot do it."""
    check_enclave(enclave)
    xml = security_xml(enclave, plugin_dir(env))
    if "</Domain>" not in uri:
        raise SecurityError("CYCLONEDDS_URI has no <Domain> element to add <Security> to")
    return uri.replace("</Domain>", xml + "</Domain>", 1)


def secure_environment(domain, env=None):
    """Before a participant in `domain` starts: when ROS 2's environment enables security,
    CYCLONEDDS_URI (in `env`, os.environ by default) gets the enclave's <Security>, unless it has
    one already (sawgui --enclave, sawdds --enclave); either way the enclave must cover the domain.
    Every sawdds participant starts through here, so a program using sawdds obeys ROS_SECURITY_*
    as the C++ programs do. Raises SecurityError as resolve_enclave and secure_uri do."""
    env = os.environ if env is None else env
    uri = env.get("CYCLONEDDS_URI", "")
    if "<Security>" not in uri:
        enclave = resolve_enclave(None, env)
        if enclave is None:
            return
        uri = env["CYCLONEDDS_URI"] = secure_uri(uri, enclave, env)
    m = re.search(r"<Governance>file:(.*?)/governance\.p7s</Governance>", uri)
    if m and os.path.isfile(os.path.join(m.group(1), "permissions.p7s")):
        try:
            enclave_check.check_domain(m.group(1), domain)
        except enclave_check.EnclaveError as e:
            raise SecurityError(f"enclave {m.group(1)}: {e}") from None
