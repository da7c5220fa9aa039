// Qualified reads over DDS: a QueryClient → Fast DDS → the gateway → the bridge → the task, in
// one process (the gateway attaches through the real shared-memory segment), loopback only.
#include <gtest/gtest.h>

#include "saw/gateway/participant.hpp"
#include "saw/gateway/query_client.hpp"
#include "served_device.hpp"

namespace {

TEST(GatewayQuery, AQualifiedReadCrossesDdsAndTheBridgeAndABadQualifierIsRefused) {
  saw::testing::ServedDevice s("gq", 30);
  saw::gateway::ParticipantConfig pc;
  pc.domain = s.domain;
  pc.name = "query-test";
  auto* p = saw::gateway::make_participant(pc);
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
  EXPECT_EQ(s.served->stats().queries, 4u);
}

}  // namespace
