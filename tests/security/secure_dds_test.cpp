// Secure participants on real Fast DDS (loopback): enclaves from one keystore talk; a participant
// without security, with another keystore's identity or with a monitor's role cannot read or
// command what it must not; expired and foreign enclaves are refused before DDS sees them, and by
// DDS when given to it directly.
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <filesystem>
#include <optional>

#include "keystore_fixture.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/security/enclave.hpp"
#include "saw/testing/dds_domain.hpp"
#include "saw/testing/wait_for.hpp"
#include "std_msgs/msg/Float64PubSubTypes.h"

namespace {

namespace fs = std::filesystem;
namespace fdds = eprosima::fastdds::dds;
using saw::security::Role;
using saw::testing::DdsDomain;
using saw::testing::TempKeystore;
using saw::testing::wait_for;
using namespace std::chrono_literals;

constexpr auto generous = 30s;  // secure discovery: a handshake per pair of participants

// One participant with a publisher and a subscriber; topics carry std_msgs/Float64.
class Peer {
 public:
  Peer(int domain, std::optional<fs::path> enclave) {
    ::unsetenv("ROS_SECURITY_ENABLE");  // no enclave means none, whatever the environment says
    saw::gateway::ParticipantConfig c;
    c.name = enclave ? enclave->filename().string() : "plain";
    c.domain = domain;
    c.enclave = std::move(enclave);
    p_ = saw::gateway::make_participant(c);
    pub_ = p_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    sub_ = p_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    type_.register_type(p_);
  }
  ~Peer() { saw::gateway::delete_participant(p_); }
  Peer(const Peer&) = delete;
  Peer& operator=(const Peer&) = delete;

  fdds::DataWriter* writer(const std::string& topic) {
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    return pub_->create_datawriter(topic_of(topic), q);
  }
  fdds::DataReader* reader(const std::string& topic) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
    return sub_->create_datareader(topic_of(topic), q);
  }

 private:
  fdds::Topic* topic_of(const std::string& name) {
    if (auto* d = p_->lookup_topicdescription(name)) return dynamic_cast<fdds::Topic*>(d);
    return p_->create_topic(name, type_.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  }
  fdds::DomainParticipant* p_ = nullptr;
  fdds::Publisher* pub_ = nullptr;
  fdds::Subscriber* sub_ = nullptr;
  fdds::TypeSupport type_{new std_msgs::msg::Float64PubSubType()};
};

void write(fdds::DataWriter* w, double v) {
  std_msgs::msg::Float64 m;
  m.data(v);
  w->write(&m);
}

// Takes what `r` has and counts the samples equal to `v` and the others.
struct Tally {
  int matching = 0, other = 0;
};
void take(fdds::DataReader* r, double v, Tally& t) {
  std_msgs::msg::Float64 m;
  fdds::SampleInfo info;
  while (r->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
    if (info.valid_data) (m.data() == v ? t.matching : t.other)++;
}

int matched(fdds::DataWriter* w) {
  fdds::PublicationMatchedStatus s;
  w->get_publication_matched_status(s);
  return s.current_count;
}
int matched(fdds::DataReader* r) {
  fdds::SubscriptionMatchedStatus s;
  r->get_subscription_matched_status(s);
  return s.current_count;
}

// Writes `v` on `w` (and `noise` on each of `others`) until `r` has taken `n` samples of `v`.
bool deliver(fdds::DataWriter* w, double v, fdds::DataReader* r, Tally& t, int n,
             std::vector<std::pair<fdds::DataWriter*, double>> others = {}) {
  return wait_for(
      [&] {
        write(w, v);
        for (auto& [o, x] : others) write(o, x);
        take(r, v, t);
        return t.matching >= n;
      },
      generous, 5ms);
}

TEST(SecureDds, AGatewayAndAnOperatorFromOneKeystoreExchangeStateAndCommands) {
  const DdsDomain domain;  // this test's alone
  TempKeystore ks("pair");
  Peer gateway(domain.id(), ks.enroll("gateway", Role::gateway)),
      op(domain.id(), ks.enroll("op", Role::operator_));
  auto* state_out = gateway.writer("rt/arm/measured_cp");
  auto* state_in = op.reader("rt/arm/measured_cp");
  auto* cmd_out = op.writer("rt/arm/servo_cf");
  auto* cmd_in = gateway.reader("rt/arm/servo_cf");
  ASSERT_TRUE(state_out && state_in && cmd_out && cmd_in);
  Tally state, cmd;
  EXPECT_TRUE(deliver(state_out, 1.5, state_in, state, 5)) << "the operator never read the gateway's state";
  EXPECT_TRUE(deliver(cmd_out, 42.0, cmd_in, cmd, 5)) << "the gateway never received the operator's command";
  EXPECT_EQ(state.other + cmd.other, 0);
}

TEST(SecureDds, ASignOnlyKeystoreStillAuthenticatesAndControlsAccess) {
  const DdsDomain domain;  // this test's alone
  saw::security::KeystoreOptions o;
  o.governance.sign_only = true;
  TempKeystore ks("sign-only", o);
  Peer gateway(domain.id(), ks.enroll("gateway", Role::gateway)),
      op(domain.id(), ks.enroll("op", Role::operator_));
  Peer plain(domain.id(), std::nullopt), monitor(domain.id(), ks.enroll("monitor", Role::monitor));
  auto* cmd_in = gateway.reader("rt/arm/servo_cf");
  auto* op_cmd = op.writer("rt/arm/servo_cf");
  auto* plain_cmd = plain.writer("rt/arm/servo_cf");
  ASSERT_TRUE(cmd_in && op_cmd && plain_cmd);
  Tally cmd;
  EXPECT_TRUE(deliver(op_cmd, 6.0, cmd_in, cmd, 20, {{plain_cmd, -1.0}}));
  EXPECT_EQ(cmd.other, 0) << "sign-only let a participant without security command";
  EXPECT_EQ(monitor.writer("rt/arm/servo_cf"), nullptr) << "sign-only let a monitor command";
}

TEST(SecureDds, AParticipantWithoutSecurityNeitherReadsStateNorDeliversCommands) {
  const DdsDomain domain;  // this test's alone
  TempKeystore ks("plain");
  Peer gateway(domain.id(), ks.enroll("gateway", Role::gateway)),
      op(domain.id(), ks.enroll("op", Role::operator_));
  Peer plain(domain.id(), std::nullopt);
  auto* state_out = gateway.writer("rt/arm/measured_cp");
  auto* cmd_in = gateway.reader("rt/arm/servo_cf");
  auto* op_state = op.reader("rt/arm/measured_cp");
  auto* op_cmd = op.writer("rt/arm/servo_cf");
  auto* plain_state = plain.reader("rt/arm/measured_cp");
  auto* plain_cmd = plain.writer("rt/arm/servo_cf");
  ASSERT_TRUE(state_out && cmd_in && op_state && op_cmd && plain_state && plain_cmd);
  // The plain writer commands all along; the operator's commands arriving bound the wait.
  Tally cmd;
  ASSERT_TRUE(deliver(op_cmd, 1.0, cmd_in, cmd, 20, {{plain_cmd, -1.0}}));
  EXPECT_EQ(cmd.other, 0) << "a command from a participant without security reached the gateway";
  Tally state, overheard;
  ASSERT_TRUE(deliver(state_out, 2.0, op_state, state, 20));
  take(plain_state, 2.0, overheard);
  EXPECT_EQ(overheard.matching + overheard.other, 0) << "a participant without security read the state";
  EXPECT_EQ(matched(plain_cmd), 0);
  EXPECT_EQ(matched(plain_state), 0);
  EXPECT_EQ(matched(state_out), 1) << "only the operator's reader";
}

TEST(SecureDds, AMonitorReadsStateButItsCommandsAreRefusedWhileAnOperatorsArrive) {
  const DdsDomain domain;  // this test's alone
  TempKeystore ks("roles");
  Peer gateway(domain.id(), ks.enroll("gateway", Role::gateway)),
      op(domain.id(), ks.enroll("op", Role::operator_)),
      monitor(domain.id(), ks.enroll("monitor", Role::monitor));
  auto* state_out = gateway.writer("rt/arm/measured_cp");
  auto* cmd_in = gateway.reader("rt/arm/servo_cf");
  auto* monitor_state = monitor.reader("rt/arm/measured_cp");
  ASSERT_TRUE(state_out && cmd_in && monitor_state);
  Tally state;
  EXPECT_TRUE(deliver(state_out, 3.0, monitor_state, state, 5)) << "the monitor never read the state";
  // Access control refuses the monitor's writer where it is made; the gateway's side would refuse
  // its samples too (its permissions travel with it), which an honest Fast DDS never gets to try.
  EXPECT_EQ(monitor.writer("rt/arm/servo_cf"), nullptr) << "a monitor may not command";
  EXPECT_EQ(op.writer("rt/arm/measured_cp"), nullptr) << "an operator may not forge state";
  EXPECT_EQ(op.writer("rt/saw/manifest"), nullptr) << "an operator may not forge the registry";
  auto* op_cmd = op.writer("rt/arm/servo_cf");
  ASSERT_NE(op_cmd, nullptr);
  Tally cmd;
  EXPECT_TRUE(deliver(op_cmd, 4.0, cmd_in, cmd, 5)) << "the operator's command never arrived";
  EXPECT_EQ(matched(cmd_in), 1) << "only the operator's writer";
}

// The files of `enclave` as Fast DDS properties, without our checks, to see DDS refuse them too.
fdds::DomainParticipant* unchecked_participant(int domain, const fs::path& e) {
  fdds::DomainParticipantQos qos;
  auto uri = [&](const char* f) { return "file://" + fs::absolute(e / f).string(); };
  auto& p = qos.properties().properties();
  p.emplace_back("dds.sec.auth.plugin", "builtin.PKI-DH");
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_ca", uri("identity_ca.cert.pem"));
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.identity_certificate", uri("cert.pem"));
  p.emplace_back("dds.sec.auth.builtin.PKI-DH.private_key", uri("key.pem"));
  p.emplace_back("dds.sec.access.plugin", "builtin.Access-Permissions");
  p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions_ca", uri("permissions_ca.cert.pem"));
  p.emplace_back("dds.sec.access.builtin.Access-Permissions.governance", uri("governance.p7s"));
  p.emplace_back("dds.sec.access.builtin.Access-Permissions.permissions", uri("permissions.p7s"));
  p.emplace_back("dds.sec.crypto.plugin", "builtin.AES-GCM-GMAC");
  // Loopback only: no interface but lo is given to UDP, and SHM stays on this host.
  qos.transport().use_builtin_transports = false;
  auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
  udp->interfaceWhiteList = {"127.0.0.1"};
  qos.transport().user_transports.push_back(udp);
  return fdds::DomainParticipantFactory::get_instance()->create_participant(domain, qos);
}

std::string refusal(int domain, const fs::path& enclave) {
  try {
    Peer p(domain, enclave);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SecureDds, AnExpiredCertificateIsRefusedWithItsDateAndDdsRefusesItToo) {
  const DdsDomain domain;  // this test's alone
  TempKeystore ks("expired");
  saw::security::EnrollOptions o;
  o.role = Role::operator_;
  o.not_before = std::chrono::system_clock::now() - std::chrono::days(30);
  o.not_after = std::chrono::system_clock::now() - std::chrono::days(1);
  const fs::path e = saw::security::enroll(ks.dir, "old", o);
  const std::string why = refusal(domain.id(), e);
  EXPECT_NE(why.find("enclave " + e.string() + ": certificate CN=/old expired on "), std::string::npos)
      << why;
  auto* p = unchecked_participant(domain.id(), e);
  EXPECT_EQ(p, nullptr) << "Fast DDS accepted an expired certificate";
  if (p != nullptr) saw::gateway::delete_participant(p);
}

TEST(SecureDds, ACertificateOfAnotherCaIsRefusedAndAnotherKeystoresPeerHearsNothing) {
  const DdsDomain domain;  // this test's alone
  TempKeystore a("ca-a", {.common_name = "lab A"}), b("ca-b", {.common_name = "lab B"});
  // Another CA's certificate beside our CAs: refused by our check and by DDS.
  const fs::path mixed = a.enroll("mixed", Role::operator_), foreign = b.enroll("op", Role::operator_);
  fs::copy_file(foreign / "cert.pem", mixed / "cert.pem", fs::copy_options::overwrite_existing);
  fs::copy_file(foreign / "key.pem", mixed / "key.pem", fs::copy_options::overwrite_existing);
  const std::string why = refusal(domain.id(), mixed);
  EXPECT_NE(why.find("is not accepted by the enclave's identity CA CN=lab A identity CA 2"),
            std::string::npos)
      << why;
  auto* p = unchecked_participant(domain.id(), mixed);
  EXPECT_EQ(p, nullptr) << "Fast DDS accepted a certificate its identity CA did not issue";
  if (p != nullptr) saw::gateway::delete_participant(p);
  // A keystore of its own is consistent, so it runs, but A's participants do not authenticate it.
  Peer gateway(domain.id(), a.enroll("gateway", Role::gateway)),
      op(domain.id(), a.enroll("op", Role::operator_)), stranger(domain.id(), foreign);
  auto* state_out = gateway.writer("rt/arm/measured_cp");
  auto* op_state = op.reader("rt/arm/measured_cp");
  auto* stranger_state = stranger.reader("rt/arm/measured_cp");
  auto* stranger_cmd = stranger.writer("rt/arm/servo_cf");
  auto* cmd_in = gateway.reader("rt/arm/servo_cf");
  ASSERT_TRUE(state_out && op_state && stranger_state && stranger_cmd && cmd_in);
  Tally state, overheard, cmd;
  ASSERT_TRUE(deliver(state_out, 5.0, op_state, state, 20, {{stranger_cmd, -1.0}}));
  take(stranger_state, 5.0, overheard);
  take(cmd_in, -1.0, cmd);
  EXPECT_EQ(overheard.matching + overheard.other, 0) << "another keystore's peer read the state";
  EXPECT_EQ(cmd.matching + cmd.other, 0) << "another keystore's peer commanded the gateway";
  EXPECT_EQ(matched(stranger_state) + matched(stranger_cmd), 0);
}

}  // namespace
