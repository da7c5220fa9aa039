// The bridge's RT paths — the exporter's per-cycle work and a proxy's commands, reads and
// events — allocate nothing and lock nothing. Server and client are two managers in this
// process, stepped alternately, talking through a real shared-memory segment.
#include <gtest/gtest.h>
#include <unistd.h>

#include <thread>

#include "alloc_guard.hpp"
#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;

class Device : public saw::Task {
 public:
  explicit Device(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    auto& p = provide("arm");
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_write<std::int64_t>("add", [this](const std::int64_t& v) { count_ += v; });
    ticked_ = &p.add_event_write<std::int64_t>("ticked");
  }
  void run() override { (void)(*ticked_)(++count_); }

 private:
  std::int64_t count_ = 0;
  saw::EventWrite<std::int64_t>* ticked_;
};

class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(1ms, 0)) {
    auto& r = require("arm");
    r.add_function("count", count_);
    r.add_function("add", add_);
    r.add_event_handler_write<std::int64_t>("ticked", [this](const std::int64_t&) { ++ticks; });
  }
  void run() override {
    std::int64_t v = 0;
    if (count_(v) == saw::Status::ok) ++reads;
    if (add_(1) == saw::Status::ok) ++writes;
  }
  int ticks = 0, reads = 0, writes = 0;

 private:
  saw::FunctionRead<std::int64_t> count_;
  saw::FunctionWrite<std::int64_t> add_;
};

TEST(AllocationGuard, BridgeExporterAndProxyDoNotAllocateOrLock) {
  const std::string name = "gdev" + std::to_string(getpid());
  Device device(name);
  saw::bridge::Exporter exporter(device, "arm");
  saw::Manager server;
  server.add(device);
  Client client;
  saw::Manager local;
  local.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  local.add(client);
  local.connect("client", "arm", name, "arm");
  server.start_stepped();
  local.start_stepped();
  server.step();
  local.step();
  saw::testing::guard_reset();
  for (int i = 0; i < 500; ++i) {
    server.step();
    local.step();
  }
  const auto counts = saw::testing::guard_counts();
  local.stop();
  server.stop();
  EXPECT_GE(client.ticks, 400);
  EXPECT_GE(client.reads, 400);
  EXPECT_GE(client.writes, 400);
  EXPECT_GE(exporter.commands_run(), 400u);
  EXPECT_EQ(counts.allocations, 0u) << "first size " << counts.first_allocation_size;
  EXPECT_EQ(counts.locks, 0u);
}

}  // namespace

namespace {

// A reconnect: the client's RT thread switches to the new server's link at its next call, with
// no allocation or lock (the monitor thread, not RT, maps and prepares it).
TEST(AllocationGuard, AProxySwitchingToANewServerDoesNotAllocateOrLock) {
  const std::string name = "gdevr" + std::to_string(getpid());
  Client client;
  saw::Manager local;
  local.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  local.add(client);
  {
    Device first(name);
    saw::bridge::Exporter exporter(first, "arm");
    saw::Manager server;
    server.add(first);
    local.connect("client", "arm", name, "arm");
    server.start_stepped();
    local.start_stepped();
    for (int i = 0; i < 10; ++i) {
      server.step();
      local.step();
    }
    server.stop();
  }  // the first server is gone: its segment is closed and unlinked
  auto* proxy = dynamic_cast<saw::bridge::Proxy*>(local.find(name));
  ASSERT_NE(proxy, nullptr);
  Device second(name);
  saw::bridge::Exporter exporter(second, "arm");
  saw::Manager server;
  server.add(second);
  server.start_stepped();
  const int ticks = client.ticks;
  saw::testing::guard_reset();
  // Steps until the monitor (polling every 10 ms) has offered the new link and the client took it.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (client.ticks < ticks + 100 && std::chrono::steady_clock::now() < deadline) {
    server.step();
    local.step();
    std::this_thread::sleep_for(100us);
  }
  const auto counts = saw::testing::guard_counts();
  local.stop();
  server.stop();
  EXPECT_EQ(proxy->reconnects(), 1u);
  EXPECT_GE(client.ticks, ticks + 100) << "events from the new server did not arrive";
  EXPECT_GE(exporter.commands_run(), 50u) << "commands did not reach the new server";
  EXPECT_EQ(counts.allocations, 0u) << "first size " << counts.first_allocation_size;
  EXPECT_EQ(counts.locks, 0u);
}

}  // namespace
