// Through both gateways on one host: a component served by gateway A is mirrored by gateway B
// under another name and reached through B's bridge segment with the ordinary connect() — state,
// write commands and qualified reads cross the bridge, Fast DDS (loopback) and the bridge again.
#include <gtest/gtest.h>
#include <unistd.h>

#include "saw/bridge/proxy.hpp"
#include "saw/testing/wait_for.hpp"
#include "served_device.hpp"

namespace {

using saw::testing::wait_for;

class Client : public saw::Component {
 public:
  Client() : Component("mirror_client") {
    auto& r = require("arm");
    r.add_function("count", count);
    r.add_function("add", add);
    r.add_function("tripled", tripled);
  }
  saw::FunctionRead<std::int64_t> count;
  saw::FunctionWrite<std::int64_t> add;
  saw::FunctionQualifiedRead<std::int64_t, std::int64_t> tripled;
};

TEST(Mirror, AComponentOfAnotherGatewayIsReachedUnderALocalNameWithQualifiedReads) {
  saw::testing::ServedDevice s("mi");
  const std::string local = s.name + "_here";
  saw::gateway::GatewayConfig config;
  config.name = "mirroring-gateway";
  config.mirrors = {s.name + "=" + local};
  config.dds.domain = s.domain;
  config.attach_timeout = 10'000'000'000;
  saw::gateway::Gateway b(config);

  Client client;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(client);
  m.connect("mirror_client", "arm", local, "arm");
  std::int64_t v = 0;
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > 10; })) << "no state arrived";
  std::int64_t r = 0;
  ASSERT_TRUE(wait_for([&] { return client.tripled(14, r) == saw::Status::ok; })) << "no reply";
  EXPECT_EQ(r, 42);
  ASSERT_EQ(client.tripled(-5, r), saw::Status::ok);
  EXPECT_EQ(r, -15);
  const std::int64_t before = v;
  ASSERT_EQ(client.add(1'000'000), saw::Status::ok);
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > before + 1'000'000; }))
      << "the write command did not reach the server";

  // Gateway A goes: the qualified read times out with an error instead of hanging.
  s.served.reset();
  ASSERT_TRUE(wait_for([&] { return client.tripled(1, r) != saw::Status::ok; }));
}

}  // namespace
