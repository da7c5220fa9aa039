"""An SROS2 enclave checked as the C++ programs check it (nonrt/security/src/enclave.cpp), in their
words, before Cyclone DDS is given it: Cyclone DDS's plugins would refuse a bad enclave too, but say
only that the participant could not be made.

The certificates and signatures are read with the `openssl` command (there is no X.509 in Python's
standard library, and sawdds adds no dependency for it); where there is no `openssl`, only the files
and the domains are checked here and Cyclone DDS's plugins check the rest.
"""
import calendar
import os
import re
import shutil
import subprocess
import time


class EnclaveError(RuntimeError):
    """What is wrong with an enclave, without the "enclave DIR: " the caller puts before it."""


def _openssl(*args, stdin=None):
    p = subprocess.run(["openssl", *args], capture_output=True, text=True, input=stdin)
    return p.returncode, p.stdout + p.stderr


def _field(path, option):
    rc, out = _openssl("x509", "-in", path, "-noout", "-nameopt", "RFC2253", option)
    if rc != 0:
        raise EnclaveError(f"{path}: not a PEM certificate")
    return out.strip().split("=", 1)[1].strip()


def _when(text):
    """OpenSSL's "Nov 26 19:47:00 2027 GMT" as seconds since the epoch."""
    return calendar.timegm(time.strptime(" ".join(text.split()), "%b %d %H:%M:%S %Y GMT"))


def _utc(t):
    return time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime(t))


def _squeezed(s):
    return re.sub(r"\s", "", s)


def _signed_text(path, ca):
    """The text of a clear-signed S/MIME document that `ca` signed, or EnclaveError as enclave.cpp says it."""
    rc, out = _openssl("smime", "-verify", "-in", path, "-CAfile", ca, "-text")
    if rc != 0:
        raise EnclaveError(f"{os.path.basename(path)} is not signed by the enclave's permissions CA "
                           f"{_field(ca, '-subject')}: signature not verified")
    return out


def _check_crl(d, subject, ca, now):
    crl = os.path.join(d, "crl.pem")
    rc, out = _openssl("crl", "-in", crl, "-CAfile", ca, "-noout")
    if rc != 0 or "verify OK" not in out:
        raise EnclaveError(f"crl.pem is not issued by the enclave's identity CA {_field(ca, '-subject')}")
    rc, text = _openssl("crl", "-in", crl, "-noout", "-text")
    m = re.search(r"Next Update: (.+)", text)
    if m and "NONE" not in m.group(1) and now > _when(m.group(1)):
        raise EnclaveError(f"crl.pem expired on {_utc(_when(m.group(1)))} (DDS Security would refuse every peer): "
                           "issue it again with `sawctl security revoke`")
    serial = _field(os.path.join(d, "cert.pem"), "-serial").upper().lstrip("0")
    for s, when in re.findall(r"Serial Number: ([0-9A-Fa-f]+)\s+Revocation Date: (.+)", text):
        if s.upper().lstrip("0") == serial:
            raise EnclaveError(f"certificate {subject} was revoked on {_utc(_when(when))} (crl.pem)")


def check_certificates(d, now=None):
    """The checks of enclave.cpp that need X.509, in its order and words: the certificate's and the
    identity CA's dates, the certificate issued by the identity CA, the key its key, governance and
    permissions signed by the permissions CA, the permissions granting the subject, crl.pem. Raises
    EnclaveError; does nothing without the `openssl` command."""
    if shutil.which("openssl") is None:
        return
    now = time.time() if now is None else now
    ca, cert = os.path.join(d, "identity_ca.cert.pem"), os.path.join(d, "cert.pem")
    subject = _field(cert, "-subject")
    not_after, not_before = _when(_field(cert, "-enddate")), _when(_field(cert, "-startdate"))
    if now > not_after:
        raise EnclaveError(f"certificate {subject} expired on {_utc(not_after)}")
    if now < not_before:
        raise EnclaveError(f"certificate {subject} is not valid before {_utc(not_before)}")
    if now > _when(_field(ca, "-enddate")):
        raise EnclaveError(f"identity CA {_field(ca, '-subject')} expired on {_utc(_when(_field(ca, '-enddate')))}")
    rc, out = _openssl("verify", "-CAfile", ca, cert)
    if rc != 0:
        m = re.search(r"error \d+ at \d+ depth lookup: (.+)", out)
        why = m.group(1).strip() if m else out.strip()
        raise EnclaveError(f"certificate {subject} (issued by {_field(cert, '-issuer')}) is not accepted by the "
                           f"enclave's identity CA {_field(ca, '-subject')}: {why} (enrolled from another keystore?)")
    rc_k, key_pub = _openssl("pkey", "-in", os.path.join(d, "key.pem"), "-pubout")
    rc_c, cert_pub = _openssl("x509", "-in", cert, "-pubkey", "-noout")
    if rc_k != 0 or rc_c != 0 or key_pub.strip() != cert_pub.strip():
        raise EnclaveError("key.pem is not the key of cert.pem")
    permissions_ca = os.path.join(d, "permissions_ca.cert.pem")
    _signed_text(os.path.join(d, "governance.p7s"), permissions_ca)
    grants = re.findall(r"<subject_name>(.*?)</subject_name>",
                        _signed_text(os.path.join(d, "permissions.p7s"), permissions_ca), re.S)
    if not any(_squeezed(g) == _squeezed(subject) for g in grants):
        raise EnclaveError(f"permissions.p7s has no grant for {subject}")
    if os.path.exists(os.path.join(d, "crl.pem")):
        _check_crl(d, subject, ca, now)


def domains(document):
    """The domain ids (inclusive ranges) of every <domains> of a governance or permissions document
    (its text; a clear-signed .p7s holds it in the clear)."""
    out = []
    for block in re.findall(r"<domains>(.*?)</domains>", document, re.S):
        for m in re.finditer(r"<id>\s*(\d+)\s*</id>|<id_range>(.*?)</id_range>", block, re.S):
            if m.group(1) is not None:
                out.append((int(m.group(1)), int(m.group(1))))
            else:
                lo = re.search(r"<min>\s*(\d+)\s*</min>", m.group(2))
                hi = re.search(r"<max>\s*(\d+)\s*</max>", m.group(2))
                out.append((int(lo.group(1)) if lo else 0, int(hi.group(1)) if hi else 232))
    return out


def _ranges_text(ranges):
    return ", ".join(str(lo) if lo == hi else f"{lo}-{hi}" for lo, hi in ranges) or "(none)"


def check_domain(d, domain):
    """EnclaveError unless the governance and the permissions of enclave `d` cover `domain`."""
    for f in ("governance.p7s", "permissions.p7s"):
        with open(os.path.join(d, f), errors="replace") as file:
            ranges = domains(file.read())
        if any(lo <= domain <= hi for lo, hi in ranges):
            continue
        if f == "governance.p7s":
            raise EnclaveError(f"domain {domain} is not in the governance's domains {_ranges_text(ranges)} ({f}): "
                               "DDS Security would refuse every topic there")
        of = f" of {_field(os.path.join(d, 'cert.pem'), '-subject')}" if shutil.which("openssl") else ""
        raise EnclaveError(f"domain {domain} is not in the permissions' domains {_ranges_text(ranges)} ({f}{of})")
