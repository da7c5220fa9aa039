// The keystore: SROS2's layout, files that OpenSSL's own command line accepts, permissions per
// role, and an enclave check that names what is wrong (expired, another CA, tampered files).
#include "saw/security/keystore.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

#include "keystore_fixture.hpp"
#include "saw/security/enclave.hpp"
#include "saw/security/policy.hpp"

namespace {

namespace fs = std::filesystem;
using saw::security::Role;
using saw::testing::TempKeystore;
using namespace std::chrono_literals;

std::string read(const fs::path& p) {
  std::ifstream in(p);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool has_openssl() { return std::system("openssl version >/dev/null 2>&1") == 0; }

int openssl(const std::string& args) { return std::system(("openssl " + args + " >/dev/null 2>&1").c_str()); }

std::string error_of(const fs::path& enclave, std::chrono::system_clock::time_point now) {
  try {
    saw::security::load_enclave(enclave, now);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(Keystore, HasSros2sLayoutWithPrivateKeysOnlyForTheOwner) {
  TempKeystore ks("layout");
  const fs::path e = ks.enroll("gateway", Role::gateway);
  EXPECT_TRUE(saw::security::is_keystore(ks.dir));
  for (const char* f :
       {"public/identity_ca.cert.pem", "public/permissions_ca.cert.pem", "private/identity_ca.key.pem",
        "private/permissions_ca.key.pem", "enclaves/governance.xml", "enclaves/governance.p7s"})
    EXPECT_TRUE(fs::is_regular_file(ks.dir / f)) << f;
  EXPECT_EQ(e, ks.dir / "enclaves" / "gateway");
  for (const char* f : {"cert.pem", "key.pem", "identity_ca.cert.pem", "permissions_ca.cert.pem",
                        "governance.p7s", "permissions.xml", "permissions.p7s"})
    EXPECT_TRUE(fs::is_regular_file(e / f)) << f;
  for (const fs::path& key : {ks.dir / "private/identity_ca.key.pem", e / "key.pem"})
    EXPECT_EQ(fs::status(key).permissions() & (fs::perms::group_all | fs::perms::others_all), fs::perms::none)
        << key;
  EXPECT_THROW(saw::security::create_keystore(ks.dir), std::runtime_error);
}

TEST(Keystore, OpensslVerifiesTheCertificatesAndTheSignedDocuments) {
  if (!has_openssl()) GTEST_SKIP() << "the openssl command is not installed";
  TempKeystore ks("openssl");
  const fs::path e = ks.enroll("lab/console", Role::operator_);
  const std::string id_ca = (ks.dir / "public/identity_ca.cert.pem").string();
  const std::string p_ca = (ks.dir / "public/permissions_ca.cert.pem").string();
  EXPECT_EQ(openssl("verify -CAfile " + id_ca + " " + (e / "cert.pem").string()), 0);
  EXPECT_NE(openssl("verify -CAfile " + p_ca + " " + (e / "cert.pem").string()), 0)
      << "the permissions CA must not have issued identities";
  for (const fs::path& doc : {e / "permissions.p7s", e / "governance.p7s"})
    EXPECT_EQ(openssl("smime -verify -text -CAfile " + p_ca + " -in " + doc.string()), 0) << doc;
  EXPECT_NE(openssl("smime -verify -text -CAfile " + id_ca + " -in " + (e / "permissions.p7s").string()), 0);
  EXPECT_EQ(openssl("pkey -check -noout -in " + (e / "key.pem").string()), 0);
  EXPECT_NE(read(e / "cert.pem").find("BEGIN CERTIFICATE"), std::string::npos);
}

TEST(Keystore, TheEnclaveCertificateNamesTheEnclaveAndItsPermissionsGrantIt) {
  TempKeystore ks("subject");
  const auto enclave = saw::security::load_enclave(ks.enroll("/lab/console", Role::monitor));
  EXPECT_EQ(enclave.subject, "CN=/lab/console");
  EXPECT_NE(read(enclave.dir / "permissions.xml").find("<subject_name>CN=/lab/console</subject_name>"),
            std::string::npos);
  EXPECT_THROW(ks.enroll("9lives", Role::monitor), std::invalid_argument);
  EXPECT_THROW(ks.enroll("a b", Role::monitor), std::invalid_argument);
  EXPECT_THROW(ks.enroll("../x", Role::monitor), std::invalid_argument);
}

TEST(Policy, MonitorsReadOperatorsAlsoCommandGatewaysDoEverything) {
  const auto m = saw::security::topic_rules(Role::monitor, {});
  EXPECT_EQ(m.publish, (std::vector<std::string>{"ros_discovery_info"}));  // ROS 2's graph, nothing of ours
  EXPECT_EQ(m.subscribe, (std::vector<std::string>{"rt/saw/manifest", "rt/*/*", "ros_discovery_info"}));
  const auto o = saw::security::topic_rules(Role::operator_, {"master", "slave"});
  EXPECT_EQ(o.publish, (std::vector<std::string>{"rt/master/*", "rt/slave/*", "rq/master/*", "rq/slave/*",
                                                 "ros_discovery_info"}));
  EXPECT_NE(std::find(o.subscribe.begin(), o.subscribe.end(), "rr/slave/*"), o.subscribe.end());
  EXPECT_NE(std::find(o.deny_publish.begin(), o.deny_publish.end(), "rt/*/measured_*"), o.deny_publish.end());
  EXPECT_NE(std::find(o.deny_publish.begin(), o.deny_publish.end(), "rt/saw/manifest"), o.deny_publish.end());
  const auto g = saw::security::topic_rules(Role::gateway, {});
  EXPECT_EQ(g.publish, (std::vector<std::string>{"rt/*", "rq/*", "rr/*", "ros_discovery_info"}));
  EXPECT_EQ(g.subscribe, g.publish);
  EXPECT_THROW(saw::security::topic_rules(Role::operator_, {"a/*"}), std::invalid_argument);
  EXPECT_EQ(saw::security::parse_role("operator"), Role::operator_);
  EXPECT_THROW(saw::security::parse_role("admin"), std::invalid_argument);
}

TEST(Policy, SubscriptionsThenDenialsThenPublicationsAndSignOnlyLeavesPayloadsClear) {
  saw::security::Grant g;
  g.subject = "CN=/op";
  g.role = Role::operator_;
  const std::string p = saw::security::permissions_xml(g);
  // The first matching rule decides: Cyclone DDS allows a topic by the first rule naming it in any
  // list (so subscriptions first), a writer by the first publish list naming it (so denials next).
  const auto subscribe = p.find("<subscribe>"), deny = p.find("<deny_rule>"),
             last_allow = p.rfind("<allow_rule>");
  ASSERT_NE(deny, std::string::npos);
  EXPECT_LT(subscribe, deny);
  EXPECT_LT(deny, last_allow);
  EXPECT_EQ(p.find("<subscribe>", last_allow), std::string::npos);
  EXPECT_NE(p.find("<default>DENY</default>"), std::string::npos);
  const std::string enc = saw::security::governance_xml({});
  EXPECT_NE(enc.find("<data_protection_kind>ENCRYPT</data_protection_kind>"), std::string::npos);
  EXPECT_NE(enc.find("<allow_unauthenticated_participants>false"), std::string::npos);
  saw::security::GovernanceOptions sign_only;
  sign_only.sign_only = true;
  const std::string sig = saw::security::governance_xml(sign_only);
  EXPECT_NE(sig.find("<data_protection_kind>NONE</data_protection_kind>"), std::string::npos);
  EXPECT_NE(sig.find("<metadata_protection_kind>SIGN</metadata_protection_kind>"), std::string::npos);
  EXPECT_NE(sig.find("<discovery_protection_kind>SIGN</discovery_protection_kind>"), std::string::npos);
}

TEST(EnclaveCheck, AnExpiredOrNotYetValidCertificateIsRefusedWithItsDate) {
  TempKeystore ks("dates");
  saw::security::EnrollOptions o;
  o.role = Role::operator_;
  o.days = 10;
  const fs::path e = saw::security::enroll(ks.dir, "op", o);
  const auto now = std::chrono::system_clock::now();
  EXPECT_EQ(error_of(e, now), "");
  const std::string expired = error_of(e, now + std::chrono::days(11));
  EXPECT_NE(expired.find("enclave " + e.string() + ": certificate CN=/op expired on "), std::string::npos)
      << expired;
  const std::string early = error_of(e, now - std::chrono::days(2));
  EXPECT_NE(early.find("is not valid before"), std::string::npos) << early;
}

TEST(EnclaveCheck, ACertificateFromAnotherKeystoreIsRefusedNamingBothCas) {
  TempKeystore a("ca-a", {.common_name = "lab A"}), b("ca-b", {.common_name = "lab B"});
  const fs::path mine = a.enroll("op", Role::operator_), theirs = b.enroll("op", Role::operator_);
  fs::copy_file(theirs / "cert.pem", mine / "cert.pem", fs::copy_options::overwrite_existing);
  fs::copy_file(theirs / "key.pem", mine / "key.pem", fs::copy_options::overwrite_existing);
  const std::string why = error_of(mine, std::chrono::system_clock::now());
  EXPECT_NE(why.find("issued by CN=lab B identity CA 2"), std::string::npos) << why;
  EXPECT_NE(why.find("identity CA CN=lab A identity CA 2"), std::string::npos) << why;
}

TEST(EnclaveCheck, TamperedOrForeignSignedDocumentsAndAWrongKeyAreRefused) {
  TempKeystore a("tamper-a"), b("tamper-b");
  const fs::path e = a.enroll("op", Role::monitor), other = b.enroll("op", Role::gateway);
  const auto now = std::chrono::system_clock::now();
  // Permissions signed by another keystore's permissions CA: a monitor that made itself a gateway.
  fs::copy_file(other / "permissions.p7s", e / "permissions.p7s", fs::copy_options::overwrite_existing);
  std::string why = error_of(e, now);
  EXPECT_NE(why.find("permissions.p7s is not signed by the enclave's permissions CA"), std::string::npos)
      << why;
  // Our own signed permissions with one word changed.
  a.enroll("op", Role::monitor);
  std::string text = read(e / "permissions.p7s");
  const auto at = text.find("<subscribe>");
  ASSERT_NE(at, std::string::npos);
  text.replace(at, 11, "<publish>  ");
  std::ofstream(e / "permissions.p7s", std::ios::trunc) << text;
  why = error_of(e, now);
  EXPECT_NE(why.find("permissions.p7s is not signed"), std::string::npos) << why;
  // The right certificate with another enclave's key.
  a.enroll("op", Role::monitor);
  fs::copy_file(a.enroll("other", Role::monitor) / "key.pem", e / "key.pem",
                fs::copy_options::overwrite_existing);
  why = error_of(e, now);
  EXPECT_NE(why.find("key.pem is not the key of cert.pem"), std::string::npos) << why;
  fs::remove(e / "governance.p7s");
  EXPECT_NE(error_of(e, now).find("missing governance.p7s"), std::string::npos);
}

TEST(EnclaveCheck, TheRos2EnvironmentNamesTheEnclaveAndNeverFallsBackToPlaintext) {
  TempKeystore ks("env");
  ks.enroll("gateway", Role::gateway);
  ::unsetenv("ROS_SECURITY_ENABLE");
  EXPECT_FALSE(saw::security::resolve_enclave(std::nullopt));
  EXPECT_EQ(saw::security::resolve_enclave(fs::path("/x")), fs::path("/x"));
  ::setenv("ROS_SECURITY_ENABLE", "true", 1);
  ::setenv("ROS_SECURITY_KEYSTORE", ks.dir.c_str(), 1);
  ::setenv("ROS_SECURITY_ENCLAVE_OVERRIDE", "/gateway", 1);
  EXPECT_EQ(saw::security::resolve_enclave(std::nullopt), ks.dir / "enclaves" / "gateway");
  ::setenv("ROS_SECURITY_ENCLAVE_OVERRIDE", "/nobody", 1);
  ::setenv("ROS_SECURITY_STRATEGY", "Permissive", 1);
  EXPECT_THROW(saw::security::resolve_enclave(std::nullopt), std::runtime_error);
  ::unsetenv("ROS_SECURITY_ENCLAVE_OVERRIDE");
  EXPECT_THROW(saw::security::resolve_enclave(std::nullopt), std::runtime_error);
  for (const char* v : {"ROS_SECURITY_ENABLE", "ROS_SECURITY_KEYSTORE", "ROS_SECURITY_STRATEGY"})
    ::unsetenv(v);
}

TEST(Keystore, AGatewaysSubjectIsOrderedForCycloneDdsPeersAndOtherRolesKeepTheirName) {
  TempKeystore ks("order");
  const auto gateway = saw::security::load_enclave(ks.enroll("gateway", Role::gateway));
  const auto viewer = saw::security::load_enclave(ks.enroll("viewer", Role::monitor));
  EXPECT_EQ(gateway.subject.rfind("serialNumber=", 0), 0u) << gateway.subject;
  EXPECT_NE(gateway.subject.find(",CN=/gateway"), std::string::npos) << gateway.subject;
  EXPECT_TRUE(gateway.peers_start_handshake);
  EXPECT_EQ(viewer.subject, "CN=/viewer");
  EXPECT_FALSE(viewer.peers_start_handshake);  // CN=/viewer's hash does not begin with 22 one bits
  EXPECT_NE(
      read(gateway.dir / "permissions.xml").find("<subject_name>" + gateway.subject + "</subject_name>"),
      std::string::npos);
}

TEST(EnclaveCheck, ADomainOutsideTheGovernanceOrThePermissionsIsNamed) {
  saw::security::KeystoreOptions o;
  o.governance.domain_min = 0;
  o.governance.domain_max = 5;
  TempKeystore ks("domain", o);
  const auto e = saw::security::load_enclave(ks.enroll("op", Role::operator_));
  EXPECT_NO_THROW(saw::security::check_domain(e, 5));
  try {
    saw::security::check_domain(e, 7);
    ADD_FAILURE() << "domain 7 accepted";
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("domain 7 is not in the governance's domains 0-5"),
              std::string::npos)
        << ex.what();
  }
}

TEST(EnclaveCheck, ARevokedCertificateIsRefusedAndTheOthersStillLoad) {
  TempKeystore ks("revoke");
  const fs::path gone = ks.enroll("gone", Role::operator_), kept = ks.enroll("kept", Role::monitor);
  EXPECT_EQ(saw::security::revoke(ks.dir, "gone"), "CN=/gone");
  EXPECT_EQ(saw::security::revoke(ks.dir, "/gone"), "CN=/gone");  // again: listed once
  for (const fs::path& e : {gone, kept}) EXPECT_TRUE(fs::is_symlink(e / "crl.pem")) << e;
  EXPECT_NE(error_of(gone, std::chrono::system_clock::now()).find("certificate CN=/gone was revoked on"),
            std::string::npos);
  const auto k = saw::security::load_enclave(kept);
  ASSERT_TRUE(k.crl.has_value());
  const fs::path later = ks.enroll("later", Role::monitor);  // enrolled after: links the CRL too
  EXPECT_TRUE(fs::is_symlink(later / "crl.pem"));
  if (!has_openssl()) GTEST_SKIP() << "the openssl command is not installed";
  const std::string ca = (ks.dir / "public/identity_ca.cert.pem").string(),
                    crl = (ks.dir / "public/crl.pem").string();
  EXPECT_EQ(openssl("crl -in " + crl + " -CAfile " + ca + " -noout"), 0);
  EXPECT_NE(
      openssl("verify -crl_check -CRLfile " + crl + " -CAfile " + ca + " " + (gone / "cert.pem").string()),
      0);
  EXPECT_EQ(
      openssl("verify -crl_check -CRLfile " + crl + " -CAfile " + ca + " " + (kept / "cert.pem").string()),
      0);
  EXPECT_THROW(saw::security::revoke(ks.dir, "nobody"), std::runtime_error);
}

TEST(Keystore, AFailedEnrolmentLeavesNothingAndAFailedReenrolmentKeepsTheOldEnclave) {
  TempKeystore ks("staging");
  const fs::path kept = ks.enroll("lab/console", Role::monitor);
  const std::string cert = read(kept / "cert.pem");
  std::ofstream(ks.dir / "private/identity_ca.key.pem", std::ios::trunc) << "not a key\n";
  EXPECT_THROW(ks.enroll("or2/nurse", Role::monitor), std::runtime_error);
  EXPECT_FALSE(fs::exists(ks.dir / "enclaves/or2"));
  EXPECT_THROW(ks.enroll("lab/console", Role::operator_), std::runtime_error);
  EXPECT_EQ(read(kept / "cert.pem"), cert);
  std::vector<std::string> in_lab;
  for (const auto& f : fs::directory_iterator(ks.dir / "enclaves/lab")) in_lab.push_back(f.path().filename());
  EXPECT_EQ(in_lab, std::vector<std::string>{"console"});
}

TEST(Keystore, ReenrollingAnEnclaveKeepsTheEnclavesInsideIt) {
  TempKeystore ks("nested");
  const fs::path lab = ks.enroll("lab", Role::monitor), console = ks.enroll("lab/console", Role::operator_);
  const std::string cert = read(lab / "cert.pem"), inner = read(console / "cert.pem");
  ks.enroll("lab", Role::operator_);
  EXPECT_NE(read(lab / "cert.pem"), cert);
  EXPECT_EQ(read(console / "cert.pem"), inner);
  EXPECT_NO_THROW(saw::security::load_enclave(lab));
  EXPECT_NO_THROW(saw::security::load_enclave(console));
  for (const auto& f : fs::directory_iterator(ks.dir / "enclaves"))
    EXPECT_NE(f.path().filename().string().front(), '.') << f.path();
}

}  // namespace
