// Qualified reads over DDS: a QueryClient → Fast DDS → the gateway → the bridge → the task, in
// one process (the gateway attaches through the real shared-memory segment), loopback only.
#include <gtest/gtest.h>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/ContentFilteredTopic.hpp>

#include "saw/gateway/participant.hpp"
#include "saw/gateway/query_client.hpp"
#include "saw/testing/wait_for.hpp"
#include "saw_msgs/msg/QueryReplyPubSubTypes.h"
#include "served_device.hpp"

namespace {

TEST(GatewayQuery, AQualifiedReadCrossesDdsAndTheBridgeAndABadQualifierIsRefused) {
  saw::testing::ServedDevice s("gq");
  auto* p = saw::testing::test_participant(s.domain, "query-test");
  {
    saw::gateway::QueryClient client(p, s.name, "tripled");
    ASSERT_TRUE(client.wait_matched(10'000'000'000)) << "the gateway's request reader did not match";
    for (std::int64_t q : {1, -7, 1'000'000'007}) {
      std::int64_t r = 0;
      ASSERT_EQ(client.call(&q, sizeof q, &r, sizeof r, 5'000'000'000), saw::Status::ok) << q;
      EXPECT_EQ(r, 3 * q);
    }
    const std::int32_t short_arg = 5;  // 4 bytes for an 8-byte qualifier
    std::int64_t r = 0;
    EXPECT_EQ(client.call(&short_arg, sizeof short_arg, &r, sizeof r, 5'000'000'000), saw::Status::invalid);
  }
  saw::gateway::delete_participant(p);
  // At least the four asked; the client asks again when a reply was lost to discovery (its reply
  // writer had not yet matched our reader), so the server may have answered one twice.
  EXPECT_GE(s.served->stats().queries, 4u);
}

}  // namespace

namespace {

namespace fdds = eprosima::fastdds::dds;

// Counts the replies a reader of the reply topic receives.
struct ReplyCounter {
  ReplyCounter(fdds::DomainParticipant* p, fdds::TopicDescription* topic)
      : subscriber(p->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT)) {
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::RELIABLE_RELIABILITY_QOS;
    q.history().kind = fdds::KEEP_ALL_HISTORY_QOS;
    q.data_sharing().off();
    reader = subscriber->create_datareader(topic, q);
  }
  int count() {
    saw_msgs::msg::QueryReply r;
    fdds::SampleInfo info;
    while (reader->take_next_sample(&r, &info) == ReturnCode_t::RETCODE_OK) taken += info.valid_data ? 1 : 0;
    return taken;
  }
  fdds::Subscriber* subscriber;
  fdds::DataReader* reader = nullptr;
  int taken = 0;
};

// A reply goes to the client that asked: another client's filtered reader receives none of it,
// while an unfiltered reader of the same topic sees every reply (so replies did flow).
TEST(GatewayQuery, RepliesAreFilteredForTheClientThatAsked) {
  saw::testing::ServedDevice s("gf");
  auto* p = saw::testing::test_participant(s.domain, "filter-test");
  {
    saw::gateway::QueryClient client(p, s.name, "tripled");
    ASSERT_TRUE(client.wait_matched(10'000'000'000));
    auto* topic = dynamic_cast<fdds::Topic*>(p->lookup_topicdescription("rr/" + s.name + "/tripledReply"));
    ASSERT_NE(topic, nullptr);
    auto* other =
        p->create_contentfilteredtopic("rr/other", topic, "client = %0", {"12345"}, "SAW_REPLY_CLIENT");
    ASSERT_NE(other, nullptr) << "the reply filter class is not registered on our participants";
    ReplyCounter all(p, topic), others(p, other);
    const auto call = [&](std::int64_t q) {
      std::int64_t r = 0;
      return client.call(&q, sizeof q, &r, sizeof r, 5'000'000'000) == saw::Status::ok && r == 3 * q;
    };
    // Until the gateway's writer has matched both readers: the unfiltered one then sees replies.
    ASSERT_TRUE(saw::testing::wait_for([&] { return call(-1) && all.count() > 0; }))
        << "no reply reached the reader";
    ASSERT_TRUE(saw::testing::wait_for([&] {
      fdds::SubscriptionMatchedStatus m;
      others.reader->get_subscription_matched_status(m);
      return m.current_count > 0;
    })) << "the filtered reader did not match the gateway's reply writer";
    const int before = all.count();
    for (std::int64_t q = 0; q < 20; ++q) ASSERT_TRUE(call(q));
    // At least the twenty: a client whose reply was lost (a reader still matching) asks again,
    // and the server answers that one twice.
    EXPECT_TRUE(saw::testing::wait_for([&] { return all.count() >= before + 20; })) << all.count() - before;
    EXPECT_EQ(others.count(), 0);
    others.subscriber->delete_datareader(others.reader);
    all.subscriber->delete_datareader(all.reader);
    p->delete_contentfilteredtopic(other);
  }
  saw::gateway::delete_participant(p);
}

}  // namespace
