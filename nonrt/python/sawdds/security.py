"""DDS Security for sawdds and sawgui: an SROS2 enclave (made by `sawctl security enroll`) as Cyclone
DDS's <Security> configuration.

An enclave is named with --enclave DIR, or by ROS 2's environment (ROS_SECURITY_ENABLE=true,
ROS_SECURITY_KEYSTORE, ROS_SECURITY_ENCLAVE_OVERRIDE; ROS_SECURITY_STRATEGY=Enforce makes a missing
one an error). Nothing here does cryptography: Cyclone DDS's own plugins do, and they must belong to
the libddsc this Python loads. PyPI's cyclonedds wheel has none; then joining a secure domain is an
error that says so, never a quiet fallback to plaintext.
"""
import glob
import os

ENCLAVE_FILES = ("cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem", "governance.p7s",
                 "permissions.p7s")


class SecurityError(RuntimeError):
    """An enclave that cannot be used, or a Cyclone DDS that cannot do security."""


def resolve_enclave(enclave=None, env=None):
    """The enclave directory to use: `enclave` if given, else ROS 2's environment's, else None
    (no security). Raises SecurityError when ROS 2's environment asks for one that is not there."""
    env = os.environ if env is None else env
    if enclave:
        return os.path.abspath(enclave)
    if env.get("ROS_SECURITY_ENABLE", "").lower() != "true":
        return None
    keystore = env.get("ROS_SECURITY_KEYSTORE", "")
    name = env.get("ROS_SECURITY_ENCLAVE_OVERRIDE", "")
    enforce = env.get("ROS_SECURITY_STRATEGY", "") == "Enforce"
    if not keystore or not name:
        if enforce:
            raise SecurityError("ROS_SECURITY_ENABLE=true with ROS_SECURITY_STRATEGY=Enforce needs "
                                "ROS_SECURITY_KEYSTORE and ROS_SECURITY_ENCLAVE_OVERRIDE")
        return None
    path = os.path.join(keystore, "enclaves", name.lstrip("/"))
    if not os.path.isdir(path) and not enforce:
        return None  # SROS2's Permissive strategy: run without
    return path


def check_enclave(path):
    """Raises SecurityError naming the first of an SROS2 enclave's files that is missing."""
    if not os.path.isdir(path):
        raise SecurityError(f"enclave {path}: no such directory")
    for f in ENCLAVE_FILES:
        if not os.path.isfile(os.path.join(path, f)):
            raise SecurityError(f"enclave {path} has no {f} (make one with: sawctl security enroll KEYSTORE NAME "
                                f"--role operator)")


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
    return ("<Security><Authentication>" + _library(plugins, "auth", "authentication") +
            f"<IdentityCA>{uri('identity_ca.cert.pem')}</IdentityCA>"
            f"<IdentityCertificate>{uri('cert.pem')}</IdentityCertificate>"
            f"<PrivateKey>{uri('key.pem')}</PrivateKey></Authentication>"
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
