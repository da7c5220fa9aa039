// A live view's stream: each row-by-row state is published on its topic at the task's rate (what a
// recorder or a program takes) and on <topic>/display at the gateway's display rate (what a GUI
// draws), and the manifest names the display topic and its rate. Real Fast DDS on loopback,
// through the real bridge, a 1 kHz task whose `count` numbers its rows.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <string>
#include <vector>

#include "saw/testing/wait_for.hpp"
#include "served_device.hpp"
#include "std_msgs/msg/Int64PubSubTypes.h"

namespace {

namespace fdds = eprosima::fastdds::dds;
using saw::testing::wait_for;

// Every `count` a topic delivered, in order (best effort, as the gateway writes state; keep all).
class Counts {
 public:
  Counts(fdds::DomainParticipant* p, fdds::Subscriber* s, const std::string& topic_name)
      : participant_(p), subscriber_(s) {
    fdds::TypeSupport type(new std_msgs::msg::Int64PubSubType());
    type.register_type(p);
    topic_ = p->create_topic(topic_name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
    q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
    q.data_sharing().off();
    reader_ = s->create_datareader(topic_, q);
  }
  ~Counts() {
    subscriber_->delete_datareader(reader_);
    participant_->delete_topic(topic_);
  }
  const std::vector<std::int64_t>& take() {
    std_msgs::msg::Int64 m;
    fdds::SampleInfo info;
    while (reader_->take_next_sample(&m, &info) == ReturnCode_t::RETCODE_OK)
      if (info.valid_data) values_.push_back(m.data());
    return values_;
  }
  // The median number of rows between two consecutive samples.
  std::int64_t median_step() {
    std::vector<std::int64_t> d;
    for (std::size_t i = 1; i < values_.size(); ++i) d.push_back(values_[i] - values_[i - 1]);
    if (d.empty()) return 0;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
    return d[d.size() / 2];
  }

 private:
  fdds::DomainParticipant* participant_;
  fdds::Subscriber* subscriber_;
  fdds::Topic* topic_;
  fdds::DataReader* reader_;
  std::vector<std::int64_t> values_;
};

TEST(GatewayDisplayStream, AStateGoesOutAtTheTasksRateAndOnItsDisplayTopicAtTheDisplayRate) {
  saw::testing::ServedDevice s("gd");  // the gateway's default display rate: 50 Hz
  const std::string topic = "rt/" + s.name + "/count";
  const auto& eps = s.served->endpoints();
  const auto e = std::find_if(eps.begin(), eps.end(), [&](const auto& x) { return x.topic == topic; });
  ASSERT_NE(e, eps.end());
  EXPECT_EQ(e->display_topic, topic + "/display") << "the manifest names the display stream";
  EXPECT_EQ(e->display_rate, 50);
  for (const auto& x : eps) {
    if (x.kind != "read") {
      EXPECT_EQ(x.display_topic, "") << x.name << ": only states have a display stream";
    }
  }

  auto* p = saw::testing::test_participant(s.domain, "display-test");
  auto* sub = p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  {
    Counts full(p, sub, topic), display(p, sub, e->display_topic);
    // 60 display samples: 1.2 s of rows at 50 Hz.
    ASSERT_TRUE(wait_for([&] { return display.take().size() >= 60 && full.take().size() >= 100; },
                         std::chrono::seconds(20)))
        << "full rate: " << full.take().size() << " samples, display: " << display.take().size();
    EXPECT_EQ(full.median_step(), 1) << "the full-rate topic carries every row of the 1 kHz task";
    // 1 kHz / 50 Hz: every 20th row, one either way as the rows' wake-up times fall about the
    // display grid.
    EXPECT_GE(display.median_step(), 19);
    EXPECT_LE(display.median_step(), 21);
  }
  p->delete_subscriber(sub);
  saw::gateway::delete_participant(p);
}

TEST(GatewayDisplayStream, ADisplayRateOfZeroPublishesNoDisplayStream) {
  saw::testing::ServedDevice s("gz", 0.0);
  for (const auto& x : s.served->endpoints()) EXPECT_EQ(x.display_topic, "") << x.name;
}

}  // namespace
