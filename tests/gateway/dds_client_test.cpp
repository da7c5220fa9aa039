// The C++ client library: a non-RT program connects to a component served by a gateway with the
// same connect() and the same functions and handlers as in the RT process. Server task, gateway
// and client are in this process; everything between them is real (bridge segment, Fast DDS on
// loopback).
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/gateway/dds_resolver.hpp"
#include "saw/gateway/gateway.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;

class Device : public saw::Task {
 public:
  explicit Device(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    auto& p = provide("arm");
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_write<std::int64_t>("add", [this](const std::int64_t& v) { count_ += v; });
    p.add_command_qualified_read<std::int64_t, std::int64_t>(
        "tripled", [](const std::int64_t& q, std::int64_t& r) { r = 3 * q; });
    ticked_ = &p.add_event_write<std::int64_t>("ticked");
  }
  void run() override {
    ++count_;
    if (count_ % 10 == 0) (void)(*ticked_)(count_);
  }

 private:
  std::int64_t count_ = 0;
  saw::EventWrite<std::int64_t>* ticked_;
};

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

template <class F>
bool wait_for(F done, std::chrono::milliseconds limit = 10s) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(1ms);
  }
  return true;
}

saw::gateway::DdsResolver::Options options(int domain) {
  saw::gateway::DdsResolver::Options o;
  o.dds.domain = domain;
  o.lookup_timeout = 10'000'000'000;
  return o;
}

TEST(DdsClient, TheSameConnectAndFunctionsReachAComponentThroughItsGateway) {
  const std::string name = "dc" + std::to_string(getpid());
  const int domain = 40 + getpid() % 60;
  Device device(name);
  saw::bridge::Exporter exporter(device, "arm");
  saw::Manager server;
  server.add(device);
  server.start();
  saw::gateway::GatewayConfig config;
  config.attach = {name};
  config.dds.domain = domain;
  saw::gateway::Gateway gateway(config);

  RemoteClient client;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::gateway::DdsResolver>(options(domain)));
  m.add(client);
  m.connect("remote_client", "arm", name, "arm");  // as for a local server
  m.start();
  std::int64_t v = 0;
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > 10; })) << "no state arrived";
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > 3; })) << "no event arrived";
  EXPECT_EQ(client.last_tick.load() % 10, 0);
  std::int64_t r = 0;
  ASSERT_EQ(client.tripled(14, r), saw::Status::ok);
  EXPECT_EQ(r, 42);
  const std::int64_t before = v;
  ASSERT_EQ(client.add(1'000'000), saw::Status::ok);
  ASSERT_TRUE(wait_for([&] { return client.count(v) == saw::Status::ok && v > before + 1'000'000; }))
      << "the write command did not reach the server";
  m.stop();
  server.stop();
}

TEST(DdsClient, ATypeMismatchFailsAtConnectNamingBothTypes) {
  const std::string name = "dct" + std::to_string(getpid());
  const int domain = 110 + getpid() % 60;
  Device device(name);
  saw::bridge::Exporter exporter(device, "arm");
  saw::Manager server;
  server.add(device);
  server.start();
  saw::gateway::GatewayConfig config;
  config.attach = {name};
  config.dds.domain = domain;
  saw::gateway::Gateway gateway(config);
  class Wrong : public saw::Component {
   public:
    Wrong() : Component("wrong") { require("arm").add_function("add", add); }
    saw::FunctionWrite<double> add;
  } wrong;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::gateway::DdsResolver>(options(domain)));
  m.add(wrong);
  try {
    m.connect("wrong", "arm", name, "arm");
    ADD_FAILURE() << "connected despite the type mismatch";
  } catch (const saw::ConnectError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("write command<double>"), std::string::npos) << msg;
    EXPECT_NE(msg.find("write command<long int>"), std::string::npos) << msg;
  }
  server.stop();
}

}  // namespace
