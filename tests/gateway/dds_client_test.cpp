// The C++ client library: a non-RT program connects to a component served by a gateway with the
// same connect() and the same functions and handlers as in the RT process. Server task, gateway
// and client are in this process; everything between them is real (bridge segment, Fast DDS on
// loopback).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "saw/gateway/dds_resolver.hpp"
#include "saw/testing/wait_for.hpp"
#include "served_device.hpp"

namespace {

using namespace std::chrono_literals;
using saw::testing::wait_for;

class RemoteClient : public saw::Task {
 public:
  RemoteClient() : Task("remote_client", saw::TaskConfig::periodic(1ms, 0)) {
    auto& r = require("arm");
    r.add_function("count", count);
    r.add_function("add", add);
    r.add_function("tripled", tripled);
    r.add_event_handler_write<std::int64_t>("ticked", [this](const std::int64_t& v) {
      ticks.fetch_add(1);
      last_tick.store(v);
    });
  }
  saw::FunctionRead<std::int64_t> count;
  saw::FunctionWrite<std::int64_t> add;
  saw::FunctionQualifiedRead<std::int64_t, std::int64_t> tripled;
  std::atomic<int> ticks{0};
  std::atomic<std::int64_t> last_tick{0};
};

saw::gateway::DdsResolver::Options options(int domain) {
  saw::gateway::DdsResolver::Options o;
  o.dds.domain = domain;
  o.lookup_timeout = 10'000'000'000;
  return o;
}

// A served device and a client of it through the DDS resolver, connected as for a local server.
struct Connected {
  explicit Connected(const char* prefix) : s(prefix) {
    m.add_resolver(std::make_unique<saw::gateway::DdsResolver>(options(s.domain)));
    m.add(client);
    m.connect("remote_client", "arm", s.name, "arm");
    m.start();
  }
  saw::testing::ServedDevice s;
  RemoteClient client;
  saw::Manager m;
};

TEST(DdsClient, TheSameConnectAndFunctionsReachAComponentThroughItsGateway) {
  Connected c("dc");
  // Named references, not a structured binding: clang 14 cannot capture those in lambdas.
  auto& s = c.s;
  auto& client = c.client;
  auto& m = c.m;
  std::int64_t v = 0;
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > 10; })) << "no state arrived";
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > 3; })) << "no event arrived";
  EXPECT_EQ(client.last_tick.load() % 10, 0);
  std::int64_t r = 0;
  ASSERT_EQ(client.tripled(14, r), saw::Status::ok);
  EXPECT_EQ(r, 42);
  const std::int64_t before = v;
  // The state reader matching says nothing about the command writer: it may match later.
  ASSERT_TRUE(wait_for([&] { return client.add(1'000'000) == saw::Status::ok; }));
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > before + 1'000'000; }))
      << "the write command did not reach the server";

  // The server's RT loop stops: its state goes stale, reads say disconnected, never hang.
  s.manager.stop();
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::disconnected; }));
  EXPECT_NE(client.tripled(1, r), saw::Status::ok);
  // The gateway goes: nothing reads the commands any more, so they are refused.
  s.served.reset();
  ASSERT_TRUE(wait_for([&] { return client.add(1) == saw::Status::disconnected; }));
  m.stop();
}

TEST(DdsClient, ATypeMismatchFailsAtConnectNamingBothTypes) {
  saw::testing::ServedDevice s("dct");
  class Wrong : public saw::Component {
   public:
    Wrong() : Component("wrong") { require("arm").add_function("add", add); }
    saw::FunctionWrite<double> add;
  } wrong;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::gateway::DdsResolver>(options(s.domain)));
  m.add(wrong);
  try {
    m.connect("wrong", "arm", s.name, "arm");
    ADD_FAILURE() << "connected despite the type mismatch";
  } catch (const saw::ConnectError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("write command<float64>"), std::string::npos) << msg;
    EXPECT_NE(msg.find("write command<int64>"), std::string::npos) << msg;
  }
}

// A component outlives the resolver that made it (a Manager drops its resolvers before its
// components): its events go on arriving, taken through the mappings the resolver loaded. With the
// resolver's registry freed under it, the component's event thread called into freed memory (a
// SIGSEGV in one run of eight at the end of the test above; under ASan, at the first event here).
TEST(DdsClient, AComponentOutlivesTheResolverThatMadeIt) {
  saw::testing::ServedDevice s("dcr");
  auto resolver = std::make_unique<saw::gateway::DdsResolver>(options(s.domain));
  std::unique_ptr<saw::Component> remote = resolver->resolve(s.name);
  ASSERT_NE(remote, nullptr);
  resolver.reset();
  RemoteClient client;
  saw::Manager m;
  m.add(std::move(remote));
  m.add(client);
  m.connect("remote_client", "arm", s.name, "arm");
  m.start();
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > 3; }))
      << "no event arrived after the resolver went";
  m.stop();
}

// A value outside the range the component declares is refused by the gateway before the bridge,
// counted, and answered on the error topic; a value inside passes.
TEST(DdsClient, AWriteOutsideTheDeclaredLimitsIsRefusedAtTheGateway) {
  Connected c("dcl");
  // Named references, not a structured binding: clang 14 cannot capture those in lambdas.
  auto& s = c.s;
  auto& client = c.client;
  auto& m = c.m;
  std::int64_t v = 0;
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > 10; }));
  // Disconnected until the gateway's command reader has matched (then nothing was published).
  ASSERT_TRUE(wait_for([&] { return client.add(20'000'000) == saw::Status::ok; }));  // refused there
  ASSERT_TRUE(wait_for([&] { return s.served->stats().rejected == 1; })) << "not refused";
  ASSERT_EQ(client.add(5'000'000), saw::Status::ok);
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > 5'000'000; }))
      << "the value inside the limits did not arrive";
  EXPECT_LT(v, 20'000'000) << "the refused value reached the server";
  EXPECT_EQ(s.served->stats().rejected, 1u);
  m.stop();
}

}  // namespace
