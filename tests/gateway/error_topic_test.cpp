// CRTK's `error` topic says why: a component's FaultInfo event and the gateway's own FAULT (the
// RT process stopped answering) arrive as text on rt/<component>/error, over real Fast DDS on
// loopback, through the real bridge segment.
#include <gtest/gtest.h>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <string>
#include <vector>

#include "crtk_msgs/msg/StringStampedPubSubTypes.h"
#include "saw/gateway/dds_resolver.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/testing/wait_for.hpp"
#include "served_device.hpp"

namespace {

namespace fdds = eprosima::fastdds::dds;
using saw::testing::wait_for;

// Every line published on one error topic, in order.
class ErrorLines {
 public:
  ErrorLines(fdds::DomainParticipant* p, const std::string& topic_name) : participant_(p) {
    fdds::TypeSupport type(new crtk_msgs::msg::StringStampedPubSubType());
    type.register_type(p);
    topic_ = p->create_topic(topic_name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    subscriber_ = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
    q.data_sharing().off();
    reader_ = subscriber_->create_datareader(topic_, q);
  }
  ~ErrorLines() {
    subscriber_->delete_datareader(reader_);
    participant_->delete_subscriber(subscriber_);
    participant_->delete_topic(topic_);
  }
  // Whether a line containing `text` has arrived.
  bool has(const std::string& text) {
    crtk_msgs::msg::StringStamped m;
    fdds::SampleInfo info;
    while (reader_->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) lines_.push_back(m.string());
    for (const auto& l : lines_)
      if (l.find(text) != std::string::npos) return true;
    return false;
  }
  std::string all() const {
    std::string s;
    for (const auto& l : lines_) s += l + "\n";
    return s;
  }

 private:
  fdds::DomainParticipant* participant_;
  fdds::Topic* topic_;
  fdds::Subscriber* subscriber_;
  fdds::DataReader* reader_;
  std::vector<std::string> lines_;
};

class Tripper : public saw::Component {
 public:
  Tripper() : Component("tripper") {
    auto& arm = require("arm");
    arm.add_function("trip", trip);
    arm.add_function("clear", clear);
  }
  saw::FunctionVoid trip, clear;
};

TEST(GatewayErrorTopic, AFaultEventAndALostRtProcessAreSaidOnTheErrorTopic) {
  saw::testing::ServedDevice s("ge");
  auto* p = saw::testing::test_participant(s.domain, "error-topic-test");
  {
    ErrorLines errors(p, "rt/" + s.name + "/error");
    saw::gateway::DdsResolver::Options o;
    o.dds.domain = s.domain;
    o.lookup_timeout = 10'000'000'000;
    Tripper tripper;
    saw::Manager m;
    m.add_resolver(std::make_unique<saw::gateway::DdsResolver>(o));
    m.add(tripper);
    m.connect("tripper", "arm", s.name, "arm");
    // Until the gateway's command reader has matched, a trip may go nowhere: ask until it is said.
    ASSERT_TRUE(wait_for([&] {
      (void)tripper.trip();
      return errors.has("FAULT: node 5 device error (code 0x2310)");
    })) << errors.all();
    // A fault of code none clears it: said as cleared, never as a FAULT a GUI would show.
    ASSERT_TRUE(wait_for([&] {
      (void)tripper.clear();
      return errors.has("fault cleared");
    })) << errors.all();
    EXPECT_FALSE(errors.has("FAULT: none")) << errors.all();
    s.manager.stop();
    ASSERT_TRUE(wait_for([&] { return errors.has("FAULT: the RT process serving it stopped answering"); }))
        << errors.all();
  }
  saw::gateway::delete_participant(p);
}

}  // namespace
