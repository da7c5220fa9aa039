// One connect(), two distances: a client task connects to a task in another process through
// the shared-memory bridge exactly as to a local one; the server dying is seen, not hung on.
#include <gtest/gtest.h>
#include <sys/mman.h>

#include <atomic>
#include <chrono>
#include <string_view>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/bridge/shm_segment.hpp"
#include "saw/manager.hpp"
#include "saw/testing/child_process.hpp"
#include "saw/testing/unique_name.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using saw::testing::unique_name;
using saw::testing::wait_for;

using namespace std::chrono_literals;

class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(1ms, 0)) {
    auto& r = require("arm");
    r.add_function("count", count_);
    r.add_function("add", add_);
    r.add_function("reset", reset_, saw::Need::optional);
    r.add_event_handler_write<std::int64_t>("ticked", [this](const std::int64_t& v) {
      ticks.fetch_add(1);
      last_tick.store(v);
    });
  }
  void run() override {
    std::int64_t v = 0;
    const auto s = count_(v);
    status.store(s);
    if (s == saw::Status::ok) count.store(v);
    if (send.exchange(false)) add_status.store(add_(1'000'000));
    cycles.fetch_add(1);
  }
  std::atomic<std::int64_t> count{0}, last_tick{0};
  std::atomic<int> ticks{0};
  std::atomic<std::uint64_t> cycles{0};
  std::atomic<bool> send{false};
  std::atomic<saw::Status> status{saw::Status::no_data}, add_status{saw::Status::no_data};

 private:
  saw::FunctionRead<std::int64_t> count_;
  saw::FunctionWrite<std::int64_t> add_;
  saw::FunctionVoid reset_;
};

// The bridge_peer program: exports `name` (also in mode v2), or in `mode` acts on it. An exporter killed with
// -9 leaves its segment: removed when the handle goes, so that runs do not litter /dev/shm.
struct Peer : saw::testing::ChildProcess {
  explicit Peer(const std::string& name, const char* mode = nullptr)
      : ChildProcess(mode == nullptr ? std::vector<std::string>{SAW_BRIDGE_PEER, name}
                                     : std::vector<std::string>{SAW_BRIDGE_PEER, mode, name}),
        segment_(mode == nullptr || std::string_view(mode) == "v2" ? "/saw." + name : std::string()) {}
  ~Peer() {
    kill9();
    if (!segment_.empty()) ::shm_unlink(segment_.c_str());
  }
  Peer(const Peer&) = delete;
  Peer& operator=(const Peer&) = delete;

 private:
  std::string segment_;
};

bool segment_ready(const std::string& name) {
  try {
    auto s = saw::bridge::ShmSegment::attach("/saw." + name);
    return saw::bridge::validate(s.data(), s.size()).empty() &&
           static_cast<const saw::bridge::SegmentHeader*>(s.data())->state.load() ==
               static_cast<std::uint32_t>(saw::bridge::SegmentState::ready);
  } catch (const saw::bridge::BridgeError&) {
    return false;
  }
}

TEST(BridgeConnect, SameConnectAcrossProcessesAndTheServerDyingIsSeen) {
  const std::string name = unique_name("bdev");
  Peer peer(name);
  ASSERT_GT(peer.pid(), 0);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); })) << "the server process did not export " << name;

  Client client;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(client);
  m.connect("client", "arm", name, "arm");  // exactly as for a local server
  m.start();
  ASSERT_TRUE(wait_for([&] { return client.count.load() > 50; })) << "state did not cross";
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > 3; })) << "events did not cross";
  EXPECT_EQ(client.last_tick.load() % 10, 0);
  const auto before = client.count.load();
  client.send.store(true);
  ASSERT_TRUE(wait_for([&] { return client.count.load() > before + 1'000'000; }))
      << "the write command did not cross";
  EXPECT_EQ(client.add_status.load(), saw::Status::ok);

  // kill -9 the server: calls fail with `disconnected` instead of hanging, and the client's loop goes on.
  peer.kill9();
  const auto killed = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_for([&] { return client.status.load() == saw::Status::disconnected; }));
  const auto seen_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - killed).count();
  RecordProperty("disconnect_seen_ms", std::to_string(seen_ms));
  std::printf("server death seen after %.1f ms\n", seen_ms);
  const auto cycles = client.cycles.load();
  ASSERT_TRUE(wait_for([&] { return client.cycles.load() > cycles + 20; })) << "the client's RT loop stopped";
  client.send.store(true);
  ASSERT_TRUE(wait_for([&] { return client.add_status.load() == saw::Status::disconnected; }));
  m.stop();
}

TEST(BridgeConnect, TypeMismatchAcrossProcessesFailsAtConnectNamingBothTypes) {
  const std::string name = unique_name("bdevt");
  Peer peer(name);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  class Wrong : public saw::Task {
   public:
    Wrong() : Task("wrong", saw::TaskConfig::periodic(1ms, 0)) { require("arm").add_function("add", add_); }
    saw::FunctionWrite<double> add_;
  } wrong;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(wrong);
  try {
    m.connect("wrong", "arm", name, "arm");
    ADD_FAILURE() << "connected despite the type mismatch";
  } catch (const saw::ConnectError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("write command<float64>"), std::string::npos) << msg;
    EXPECT_NE(msg.find("write command<int64>"), std::string::npos) << msg;
  }
}

TEST(BridgeConnect, AStaleSegmentIsRefusedAtConnect) {
  const std::string name = unique_name("bdevs");
  Peer peer(name);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  peer.kill9();                        // the segment stays (until `peer` goes), its heartbeat stops
  std::this_thread::sleep_for(150ms);  // let the heartbeat age past the 100 ms limit (not a race: a bound)
  Client client;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(client);
  try {
    m.connect("client", "arm", name, "arm");
    ADD_FAILURE();
  } catch (const saw::ConnectError& e) {
    EXPECT_NE(std::string(e.what()).find("is not running"), std::string::npos) << e.what();
  }
}

}  // namespace

namespace {

// A local task exported with ONE client slot: a second client can only connect if the slot of a
// client killed with -9 is reclaimed. The server keeps running meanwhile.
class Counter : public saw::Task {
 public:
  explicit Counter(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    auto& p = provide("arm");
    p.add_command_read("count", state_table().add_column("count", &count_));
    p.add_command_write<std::int64_t>("add", [this](const std::int64_t& v) {
      count_ += v;
      adds.fetch_add(1);
    });
  }
  std::atomic<std::int64_t> adds{0};

 private:
  std::int64_t count_ = 0;
};

TEST(BridgeConnect, AKilledClientsSlotIsReclaimedAndTheServerRunsOn) {
  const std::string name = unique_name("bsrv");
  Counter counter(name);
  saw::bridge::Exporter exporter(counter, "arm", /*slots=*/1);
  saw::Manager m;
  m.add(counter);
  m.start();
  std::uint64_t overruns_before = 0;
  {
    Peer first(name, "client");
    ASSERT_TRUE(wait_for([&] { return counter.adds.load() > 50; }))
        << "the first client's commands did not arrive";
    overruns_before = counter.statistics().overruns;
  }  // kill -9
  const auto adds = counter.adds.load();
  const auto cycles = counter.statistics().cycles;
  ASSERT_TRUE(wait_for([&] { return counter.statistics().cycles > cycles + 50; })) << "the server stopped";
  // A figure, not an assertion (overruns on a VM come from the host): the exporter never waits
  // for a client, so a dead one cannot hold the server's cycle.
  std::printf("server overruns while a client was killed: %llu\n",
              static_cast<unsigned long long>(counter.statistics().overruns - overruns_before));
  EXPECT_LE(counter.adds.load(), adds + 1) << "nothing arrives from a dead client";
  // Its heartbeat stopped: the slot is freed after the client timeout.
  ASSERT_TRUE(wait_for([&] { return exporter.slots_reclaimed() == 1; }))
      << "the dead client's slot stayed taken";
  Peer second(name, "client");  // needs the dead client's slot
  ASSERT_TRUE(wait_for([&] { return counter.adds.load() > adds + 50; }))
      << "the second client could not connect";
  m.stop();
}

}  // namespace

namespace {

TEST(BridgeConnect, QualifiedReadsCrossForNonRtCallersAndAreRefusedToRtTasks) {
  const std::string name = unique_name("bdevq");
  Peer peer(name);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  class Caller : public saw::Component {
   public:
    Caller() : Component("caller") { require("arm").add_function("tripled", tripled); }
    saw::FunctionQualifiedRead<std::int64_t, std::int64_t> tripled;
  } caller;
  class RtCaller : public saw::Task {
   public:
    RtCaller() : Task("rt_caller", saw::TaskConfig::periodic(1ms, 80)) {
      require("arm").add_function("tripled", tripled);
    }
    saw::FunctionQualifiedRead<std::int64_t, std::int64_t> tripled;
  } rt_caller;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(caller);
  m.add(rt_caller);
  try {
    m.connect("rt_caller", "arm", name, "arm");
    ADD_FAILURE() << "an RT task was allowed to wait for another process";
  } catch (const saw::ConnectError& e) {
    EXPECT_NE(std::string(e.what()).find("real-time task 'rt_caller'"), std::string::npos) << e.what();
  }
  m.connect("caller", "arm", name, "arm");
  std::int64_t r = 0;
  for (std::int64_t q : {1, 7, -5, 1'000'000}) {
    ASSERT_EQ(caller.tripled(q, r), saw::Status::ok);
    EXPECT_EQ(r, 3 * q);
  }
  peer.kill9();
  // Never hangs: a dead server answers `disconnected` (stale heartbeat) or `timeout`.
  ASSERT_TRUE(wait_for([&] {
    const auto s = caller.tripled(2, r);
    return s == saw::Status::disconnected || s == saw::Status::timeout;
  }));
}

}  // namespace

namespace {

TEST(BridgeConnect, AClientReconnectsWhenANewServerWithTheSameNameStarts) {
  const std::string name = unique_name("bdevr");
  auto first = std::make_unique<Peer>(name);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  Client client;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(client);
  m.connect("client", "arm", name, "arm");
  m.start();
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > 3; }));
  auto* proxy = dynamic_cast<saw::bridge::Proxy*>(m.find(name));
  ASSERT_NE(proxy, nullptr);
  EXPECT_EQ(proxy->reconnects(), 0u);

  first.reset();  // kill -9
  ASSERT_TRUE(wait_for([&] { return client.status.load() == saw::Status::disconnected; }));
  EXPECT_EQ(proxy->reconnects(), 0u) << "nothing to reconnect to yet";

  Peer second(name);  // a new server process under the same name: a new segment, count from 0
  const auto started = std::chrono::steady_clock::now();
  ASSERT_TRUE(wait_for([&] { return client.status.load() == saw::Status::ok; }))
      << "the client did not reconnect";
  std::printf("reconnected %.1f ms after the new server was spawned\n",
              std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count());
  EXPECT_EQ(proxy->reconnects(), 1u);
  // State, events and commands all come from the new server.
  const int ticks = client.ticks.load();
  ASSERT_TRUE(wait_for([&] { return client.ticks.load() > ticks + 3; })) << "events did not resume";
  const auto before = client.count.load();
  EXPECT_LT(before, 1'000'000) << "the count comes from the new server";
  client.send.store(true);
  ASSERT_TRUE(wait_for([&] { return client.count.load() > before + 1'000'000; }))
      << "commands did not reach the new server";
  EXPECT_EQ(client.add_status.load(), saw::Status::ok);
  m.stop();
}

}  // namespace

// The test's version of a type the peer's `v2` mode exports with layout version 2.
namespace probe {
struct Sample {
  static constexpr std::string_view type_name = "probe::Sample";
  static constexpr std::uint32_t layout_version = 1;
  double a = 0, b = 0;
};
}  // namespace probe

namespace {

TEST(BridgeConnect, ATypeWithAnotherLayoutVersionFailsAtConnectNamingBoth) {
  const std::string name = unique_name("bdevv");
  Peer peer(name, "v2");
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  class Setter : public saw::Task {
   public:
    Setter() : Task("setter", saw::TaskConfig::periodic(1ms, 0)) { require("arm").add_function("set", set_); }
    saw::FunctionWrite<probe::Sample> set_;
  } setter;
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(setter);
  try {
    m.connect("setter", "arm", name, "arm");
    ADD_FAILURE() << "connected to a type of another layout";
  } catch (const saw::ConnectError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("probe::Sample (layout v1, 16 B)"), std::string::npos) << msg;
    EXPECT_NE(msg.find("probe::Sample (layout v2, 16 B)"), std::string::npos) << msg;
  }
}

TEST(BridgeExport, ATypeWithoutALayoutVersionIsRefusedNamingItAndTheFix) {
  struct Unversioned {
    double x = 0;
  };
  class Owner : public saw::Task {
   public:
    Owner() : Task(unique_name("owner"), saw::TaskConfig::periodic(1ms, 0)) {
      provide("arm").add_command_write<Unversioned>("set", [](const Unversioned&) {});
    }
  } owner;
  try {
    saw::bridge::Exporter exporter(owner, "arm");
    ADD_FAILURE() << "exported a type without a layout version";
  } catch (const saw::bridge::BridgeError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("Unversioned"), std::string::npos) << msg;
    EXPECT_NE(msg.find("layout_version"), std::string::npos) << msg;
  }
}

TEST(BridgeConnect, ANonRtConsumerSleepsUntilTheServerPublishesARow) {
  const std::string name = unique_name("bdevw");
  auto peer = std::make_unique<Peer>(name);
  ASSERT_TRUE(wait_for([&] { return segment_ready(name); }));
  saw::bridge::ShmResolver resolver;
  auto component = resolver.resolve(name);
  ASSERT_NE(component, nullptr);
  auto& proxy = dynamic_cast<saw::bridge::Proxy&>(*component);
  std::uint32_t seen = 0;
  int updates = 0;
  for (int i = 0; i < 50; ++i) updates += proxy.wait_for_update(seen, 1'000'000'000) ? 1 : 0;
  EXPECT_EQ(updates, 50) << "every wait ends with a new row from the 1 kHz server";
  peer.reset();                                  // kill -9: no more rows; the wait ends at its timeout
  (void)proxy.wait_for_update(seen, 5'000'000);  // a row may have been in flight
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(proxy.wait_for_update(seen, 30'000'000));
  EXPECT_GE(std::chrono::steady_clock::now() - t0, 30ms);
}

}  // namespace

namespace {

TEST(BridgeConnect, AFullCommandRingIsAnErrorReturnedAndCounted) {
  const std::string name = unique_name("bfull");
  Counter counter(name);  // never started: nothing drains its slots
  saw::bridge::Exporter exporter(counter, "arm", {.slots = 1, .ring_capacity = 4});
  class Caller : public saw::Component {
   public:
    Caller() : Component("caller") { require("arm").add_function("add", add); }
    saw::FunctionWrite<std::int64_t> add;
  } caller;
  saw::Manager m;
  // A generous staleness limit: the unstarted server's heartbeat is the exporter's first one.
  m.add_resolver(
      std::make_unique<saw::bridge::ShmResolver>(saw::bridge::ProxyOptions{.stale_after = 60'000'000'000}));
  m.add(caller);
  m.connect("caller", "arm", name, "arm");
  int ok = 0, full = 0;
  for (int i = 0; i < 10; ++i) {
    const auto s = caller.add(1);
    ok += s == saw::Status::ok;
    full += s == saw::Status::queue_full;
  }
  EXPECT_EQ(ok, 4);
  EXPECT_EQ(full, 6);
  EXPECT_EQ(dynamic_cast<saw::bridge::Proxy*>(m.find(name))->commands_refused(), 6u);
}

}  // namespace

namespace {

// A client without a thread cannot drain a remote server's event ring: check() says so, and
// connect() refuses before binding anything, not even the client's commands.
TEST(BridgeConnect, AClientWithoutAThreadIsRefusedRemoteEventsBeforeAnythingIsBound) {
  class Ticker : public saw::Task {
   public:
    explicit Ticker(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
      auto& p = provide("arm");
      p.add_command_write<std::int64_t>("add", [](const std::int64_t&) {});
      p.add_event_write<std::int64_t>("ticked");
    }
  };
  class Passive : public saw::Component {
   public:
    Passive() : Component("passive") {
      auto& r = require("arm");
      r.add_function("add", add);
      r.add_event_handler_write<std::int64_t>("ticked", [](const std::int64_t&) {});
    }
    saw::FunctionWrite<std::int64_t> add;
  } passive;
  const std::string name = unique_name("bpas");
  Ticker ticker(name);
  saw::bridge::Exporter exporter(ticker, "arm");
  saw::Manager m;
  m.add_resolver(std::make_unique<saw::bridge::ShmResolver>());
  m.add(passive);
  const auto error = m.check("passive", "arm", name, "arm");
  ASSERT_TRUE(error.has_value());
  EXPECT_NE(std::string(error->what()).find("without a thread"), std::string::npos) << error->what();
  EXPECT_NE(m.find(name), nullptr) << "check() keeps the proxy it resolved, as connect() would";
  EXPECT_THROW(m.connect("passive", "arm", name, "arm"), saw::ConnectError);
  EXPECT_FALSE(passive.add.is_bound());
  EXPECT_FALSE(passive.required("arm")->is_connected());
}

}  // namespace
