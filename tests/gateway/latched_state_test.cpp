// What a late joiner needs is there when it joins: a component's operating state is latched on
// its DDS topic (transient local, keep last 1) and published when the gateway attaches, so a
// reader created long after the last change still gets it at once; so is a setting's read-back
// (`gain` beside `set_gain`), and the manifest says which topics are latched; a gateway that
// leaves because its RT process died says FAULT first. Real Fast DDS on loopback, through the real bridge.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <string>
#include <vector>

#include "crtk_msgs/msg/OperatingStatePubSubTypes.h"
#include "saw/bridge/exporter.hpp"
#include "saw/crtk.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/manager.hpp"
#include "saw/testing/dds_domain.hpp"
#include "saw/testing/unique_name.hpp"
#include "saw/testing/wait_for.hpp"
#include "std_msgs/msg/Float64PubSubTypes.h"

namespace {

namespace fdds = eprosima::fastdds::dds;
using saw::testing::wait_for;

// Provided "arm": operating_state as a read (state table) and as an event on change, as every
// CRTK device of ours has it. It starts ENABLED and changes only when the test asks.
class StatefulDevice : public saw::Task {
 public:
  explicit StatefulDevice(std::string name)
      : Task(std::move(name), saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0)) {
    auto& p = provide("arm");
    p.add_command_read("operating_state", state_table().add_column("operating_state", &state_));
    changed_ = &p.add_event_write<saw::OperatingState>("operating_state");
    // A setting: written with set_gain, read back as gain.
    p.add_command_write<double>("set_gain", [this](const double& g) { gain_ = g; });
    p.add_command_read("gain", state_table().add_column("gain", &gain_));
    p.add_command_read("cycles", state_table().add_column("cycles", &cycles_));
    state_.state = saw::OperatingStateValue::enabled;
  }
  void request(saw::OperatingStateValue v) {
    requested_.store(static_cast<int>(v), std::memory_order_release);
  }
  void run() override {
    ++cycles_;
    const int r = requested_.exchange(-1, std::memory_order_acq_rel);
    if (r < 0) return;
    state_.state = static_cast<saw::OperatingStateValue>(r);
    (void)(*changed_)(state_);
  }

 private:
  saw::OperatingState state_;
  double gain_ = 2.5;
  std::int64_t cycles_ = 0;
  saw::EventWrite<saw::OperatingState>* changed_;
  std::atomic<int> requested_{-1};
};

struct Served {
  Served()
      : name(saw::testing::unique_name("latch")), domain(claim.id()), device(name), exporter(device, "arm") {
    manager.add(device);
    manager.start();
    saw::gateway::GatewayConfig config;
    config.attach = {name};
    config.dds.domain = domain;
    gateway = std::make_unique<saw::gateway::Gateway>(config);
  }
  ~Served() {
    gateway.reset();
    manager.stop();
  }
  std::string name;
  saw::testing::DdsDomain claim;  // held while the device is served
  int domain;
  StatefulDevice device;
  saw::bridge::Exporter exporter;
  saw::Manager manager;
  std::unique_ptr<saw::gateway::Gateway> gateway;
};

// A reader of one operating-state topic asking for what was written before it joined, as a GUI
// or `sawctl echo` does.
class StateReader {
 public:
  StateReader(fdds::DomainParticipant* p, fdds::Topic* topic)
      : subscriber_(p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT)) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
    q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
    q.data_sharing().off();
    reader_ = subscriber_->create_datareader(topic, q);
  }
  // Every state received so far, in order.
  const std::vector<std::string>& states() {
    crtk_msgs::msg::OperatingState m;
    fdds::SampleInfo info;
    while (reader_->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) states_.push_back(m.state());
    return states_;
  }
  bool saw(const std::string& state) {
    for (const auto& s : states())
      if (s == state) return true;
    return false;
  }
  std::string all() {
    std::string s;
    for (const auto& x : states()) s += x + " ";
    return s;
  }
  void close(fdds::DomainParticipant* p) {
    subscriber_->delete_datareader(reader_);
    p->delete_subscriber(subscriber_);
  }

 private:
  fdds::Subscriber* subscriber_;
  fdds::DataReader* reader_ = nullptr;
  std::vector<std::string> states_;
};

class GatewayLatching : public ::testing::Test {
 protected:
  void SetUp() override {
    saw::gateway::ParticipantConfig pc;
    pc.domain = served.domain;
    pc.name = "latch-test";
    participant = saw::gateway::make_participant(pc);
    fdds::TypeSupport type(new crtk_msgs::msg::OperatingStatePubSubType());
    type.register_type(participant);
    topic = participant->create_topic("rt/" + served.name + "/operating_state", type.get_type_name(),
                                      fdds::TOPIC_QOS_DEFAULT);
  }
  void TearDown() override {
    participant->delete_topic(topic);
    saw::gateway::delete_participant(participant);
  }
  Served served;
  fdds::DomainParticipant* participant = nullptr;
  fdds::Topic* topic = nullptr;
};

TEST_F(GatewayLatching, ALateReaderGetsTheCurrentStateWithoutAnyChange) {
  // The device has not changed state since before the gateway attached: no event was ever
  // raised, so only the gateway's publication at attach time can have said ENABLED.
  StateReader first(participant, topic);
  ASSERT_TRUE(wait_for([&] { return first.saw("ENABLED"); })) << first.all();

  served.device.request(saw::OperatingStateValue::disabled);
  ASSERT_TRUE(wait_for([&] { return first.saw("DISABLED"); })) << first.all();

  // Joins after the change: its first (and only) sample is the newest state, not the history.
  StateReader late(participant, topic);
  ASSERT_TRUE(wait_for([&] { return !late.states().empty(); }));
  EXPECT_EQ(late.states().front(), "DISABLED") << late.all();
  EXPECT_FALSE(late.saw("ENABLED")) << late.all();
  late.close(participant);
  first.close(participant);
}

TEST_F(GatewayLatching, AGatewayLeavingForItsDeadRtProcessSaysFaultFirst) {
  StateReader reader(participant, topic);
  ASSERT_TRUE(wait_for([&] { return reader.saw("ENABLED"); })) << reader.all();
  served.gateway->announce_exit("the RT process (pid 1234) exited");
  ASSERT_TRUE(wait_for([&] { return reader.saw("FAULT"); })) << reader.all();
  // Latched: a reader joining while the gateway is still there sees FAULT, not the old state.
  StateReader late(participant, topic);
  ASSERT_TRUE(wait_for([&] { return !late.states().empty(); }));
  EXPECT_EQ(late.states().front(), "FAULT") << late.all();
  late.close(participant);
  reader.close(participant);
}

TEST_F(GatewayLatching, ASettingsReadBackIsLatchedAndTheManifestSaysWhich) {
  const auto latched = [&](const std::string& name) {
    for (const auto& e : served.gateway->endpoints())
      if (e.name == name && e.kind == "read") return e.latched;
    ADD_FAILURE() << "no read " << name;
    return false;
  };
  EXPECT_TRUE(latched("operating_state"));
  EXPECT_TRUE(latched("gain")) << "the read-back of set_gain";
  EXPECT_FALSE(latched("cycles")) << "a value of every row";
  // A reader joining long after the value was set gets it at once, though it never changed.
  fdds::TypeSupport type(new std_msgs::msg::Float64PubSubType());
  type.register_type(participant);
  auto* gain =
      participant->create_topic("rt/" + served.name + "/gain", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  auto* sub = participant->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
  q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
  q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
  q.data_sharing().off();
  auto* reader = sub->create_datareader(gain, q);
  std::vector<double> seen;
  ASSERT_TRUE(wait_for([&] {
    std_msgs::msg::Float64 m;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) seen.push_back(m.data());
    return !seen.empty();
  }));
  EXPECT_EQ(seen.front(), 2.5);
  sub->delete_datareader(reader);
  participant->delete_subscriber(sub);
  participant->delete_topic(gain);
}

}  // namespace
