"""A DDS Security keystore made as SROS2 makes it, written apart from our keystore code.

SROS2 (ros2/sros2, sros2/keystore/_keystore.py, _enclave.py, _utilities.py) makes one CA key
(ECDSA prime256v1, CN=sros2CA, basicConstraints critical CA:TRUE pathlen 1 and no other extension:
no subject or authority key identifier) in public/ca.cert.pem and private/ca.key.pem, links
identity_ca and permissions_ca to it in both folders, signs its default governance (one domain,
ROS_DOMAIN_ID) as clear-signed S/MIME, and gives each enclave a key (PKCS#8), a certificate
CN=/NAME signed by the CA (basicConstraints CA:FALSE, not critical, nothing else), links to the CA
certificates and the governance, and permissions from its default policy (every topic, service and
action: rt/*, rq/*Request, rr/*Reply). SROS2 does this with Python's `cryptography`; here the
`openssl` command does the same, as SROS2's first releases did. SROS2 starts validity a day early;
`openssl x509 -req` (3.0) cannot, so these start now.
"""
import os
import subprocess

GOVERNANCE = """<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"
    xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
    <domain_access_rules>
        <domain_rule>
            <domains>
              <id>{domain}</id>
            </domains>
            <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
            <enable_join_access_control>true</enable_join_access_control>
            <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
            <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
            <rtps_protection_kind>SIGN</rtps_protection_kind>
            <topic_access_rules>
                <topic_rule>
                    <topic_expression>*</topic_expression>
                    <enable_discovery_protection>true</enable_discovery_protection>
                    <enable_liveliness_protection>true</enable_liveliness_protection>
                    <enable_read_access_control>true</enable_read_access_control>
                    <enable_write_access_control>true</enable_write_access_control>
                    <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
                    <data_protection_kind>ENCRYPT</data_protection_kind>
                </topic_rule>
            </topic_access_rules>
        </domain_rule>
    </domain_access_rules>
</dds>
"""

# SROS2's default policy (every topic, service and action) as its permissions.xsl renders it.
PERMISSIONS = """<?xml version="1.0" encoding="UTF-8"?>
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name="{name}">
      <subject_name>CN={name}</subject_name>
      <validity>
        <not_before>2020-01-01T00:00:00</not_before>
        <not_after>2035-01-01T00:00:00</not_after>
      </validity>
      <allow_rule>
        <domains>
          <id>{domain}</id>
        </domains>
        <publish>
          <topics>
            <topic>rq/*Request</topic>
            <topic>rr/*Reply</topic>
            <topic>rt/*</topic>
            <topic>ros_discovery_info</topic>
          </topics>
        </publish>
        <subscribe>
          <topics>
            <topic>rq/*Request</topic>
            <topic>rr/*Reply</topic>
            <topic>rt/*</topic>
            <topic>ros_discovery_info</topic>
          </topics>
        </subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
"""

# Extensions exactly as SROS2's CertificateBuilder adds them: OpenSSL 3 adds key identifiers unless told not to.
OPENSSL_CNF = """[req]
distinguished_name = dn
prompt = no
[dn]
[ca]
basicConstraints = critical,CA:TRUE,pathlen:1
subjectKeyIdentifier = none
authorityKeyIdentifier = none
[leaf]
basicConstraints = CA:FALSE
subjectKeyIdentifier = none
authorityKeyIdentifier = none
"""


def _openssl(*args, cwd=None):
    r = subprocess.run(["openssl", *args], capture_output=True, text=True, cwd=cwd)
    if r.returncode != 0:
        raise RuntimeError(f"openssl {' '.join(args)}: {r.stderr.strip()}")
    return r.stdout


def _key(path):
    _openssl("genpkey", "-algorithm", "EC", "-pkeyopt", "ec_paramgen_curve:prime256v1", "-out", path)
    os.chmod(path, 0o600)


def _sign(ks, text_path, out_path):
    _openssl("smime", "-sign", "-text", "-in", text_path, "-out", out_path, "-signer",
             os.path.join(ks, "public", "permissions_ca.cert.pem"), "-inkey",
             os.path.join(ks, "private", "permissions_ca.key.pem"))


def _link(target, link):
    if os.path.lexists(link):
        os.remove(link)
    os.symlink(os.path.relpath(target, os.path.dirname(link)), link)


def create_keystore(ks, domain):
    """`ros2 security create_keystore KS` with ROS_DOMAIN_ID=domain."""
    for d in ("public", "private", "enclaves"):
        os.makedirs(os.path.join(ks, d), exist_ok=True)
    cnf = os.path.join(ks, "openssl.cnf")
    with open(cnf, "w") as f:
        f.write(OPENSSL_CNF)
    key, cert = os.path.join(ks, "private", "ca.key.pem"), os.path.join(ks, "public", "ca.cert.pem")
    _key(key)
    _openssl("req", "-new", "-x509", "-config", cnf, "-extensions", "ca", "-key", key, "-subj", "/CN=sros2CA",
             "-days", "3650", "-sha256", "-out", cert)
    os.remove(cnf)
    for which in ("identity_ca", "permissions_ca"):
        _link(cert, os.path.join(ks, "public", which + ".cert.pem"))
        _link(key, os.path.join(ks, "private", which + ".key.pem"))
    gov = os.path.join(ks, "enclaves", "governance.xml")
    with open(gov, "w") as f:
        f.write(GOVERNANCE.format(domain=domain))
    _sign(ks, gov, os.path.join(ks, "enclaves", "governance.p7s"))


def create_enclave(ks, name, domain):
    """`ros2 security create_enclave KS NAME` (NAME such as /viewer) with ROS_DOMAIN_ID=domain."""
    d = os.path.join(ks, "enclaves", name.lstrip("/"))
    os.makedirs(d, exist_ok=True)
    for which in ("identity_ca", "permissions_ca"):
        _link(os.path.join(ks, "public", which + ".cert.pem"), os.path.join(d, which + ".cert.pem"))
    _link(os.path.join(ks, "enclaves", "governance.p7s"), os.path.join(d, "governance.p7s"))
    cnf = os.path.join(d, "openssl.cnf")
    with open(cnf, "w") as f:
        f.write(OPENSSL_CNF)
    key, csr, cert = (os.path.join(d, f) for f in ("key.pem", "req.csr", "cert.pem"))
    _key(key)
    subject = "/CN=" + name.replace("/", "\\/")  # the name's '/' are part of the value, not RDN separators
    _openssl("req", "-new", "-config", cnf, "-key", key, "-subj", subject, "-out", csr)
    _openssl("x509", "-req", "-in", csr, "-CA", os.path.join(ks, "public", "identity_ca.cert.pem"), "-CAkey",
             os.path.join(ks, "private", "identity_ca.key.pem"),
             "-set_serial", str(int.from_bytes(os.urandom(19), "big")),
             "-days", "3650", "-sha256", "-extfile", cnf, "-extensions", "leaf", "-out", cert)
    os.remove(csr)
    os.remove(cnf)
    perm = os.path.join(d, "permissions.xml")
    with open(perm, "w") as f:
        f.write(PERMISSIONS.format(name=name, domain=domain))
    _sign(ks, perm, os.path.join(d, "permissions.p7s"))
    return d
