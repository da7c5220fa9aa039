// Qualified reads over DDS: a QueryClient → Fast DDS → the gateway → the bridge → the task, in
// one process (the gateway attaches through the real shared-memory segment), loopback only.
#include <gtest/gtest.h>
#include <unistd.h>

#include "saw/bridge/exporter.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/gateway/participant.hpp"
#include "saw/gateway/query_client.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;

class Server : public saw::Task {
 public:
  explicit Server(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    provide("arm").add_command_qualified_read<std::int64_t, std::int64_t>(
        "tripled", [](const std::int64_t& q, std::int64_t& r) { r = 3 * q; });
  }
};

TEST(GatewayQuery, AQualifiedReadCrossesDdsAndTheBridgeAndABadQualifierIsRefused) {
  const std::string name = "gq" + std::to_string(getpid());
  const int domain = 30 + getpid() % 60;
  Server server(name);
  saw::bridge::Exporter exporter(server, "arm");
  saw::Manager m;
  m.add(server);
  m.start();
  saw::gateway::GatewayConfig config;
  config.attach = {name};
  config.dds.domain = domain;
  saw::gateway::Gateway gateway(config);
  saw::gateway::ParticipantConfig pc;
  pc.domain = domain;
  pc.name = "query-test";
  auto* p = saw::gateway::make_participant(pc);
  {
    saw::gateway::QueryClient client(p, name, "tripled");
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
  EXPECT_EQ(gateway.stats().queries, 4u);
  m.stop();
}

}  // namespace
