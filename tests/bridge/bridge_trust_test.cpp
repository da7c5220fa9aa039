// The bridge trusts no peer: a client process that writes anything anywhere in a server's
// segment can neither crash the server, move its writes, nor make it run a bad command.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "saw/bridge/exporter.hpp"
#include "saw/bridge/proxy.hpp"
#include "saw/crtk.hpp"
#include "saw/manager.hpp"
#include "saw/testing/child_process.hpp"
#include "saw/testing/unique_name.hpp"
#include "saw/testing/wait_for.hpp"

namespace {

using saw::testing::in_child;
using saw::testing::unique_name;
using saw::testing::wait_for;

using namespace std::chrono_literals;
using namespace saw::bridge;

constexpr double force_limit = 5.0;

// A device that records what reaches it: every force must be finite and within its limits.
class Device : public saw::Task {
 public:
  explicit Device(std::string name) : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    auto& p = provide("arm");
    p.add_command_read("measured", state_table().add_column("measured", &measured_));
    p.add_command_write<saw::Wrench>("servo_cf", [this](const saw::Wrench& w) {
      for (double f : w.force)
        if (!std::isfinite(f) || std::abs(f) > force_limit) bad.fetch_add(1);
      applied.fetch_add(1);
    });
    p.limit("servo_cf", -force_limit, force_limit);
    p.add_command_write<saw::StateCommand>("state_command", [this](const saw::StateCommand& c) {
      if (static_cast<unsigned>(c) > static_cast<unsigned>(saw::StateCommand::home)) bad.fetch_add(1);
      states.fetch_add(1);
    });
    p.add_command_void("home", [this] { homes.fetch_add(1); });
    p.add_command_qualified_read<double, double>("twice", [](const double& q, double& r) { r = 2 * q; });
    button_ = &p.add_event_write<saw::ButtonEvent>("button");
  }
  void run() override {
    measured_[0] += 1e-3;
    if (++cycle_ % 20 == 0) (void)(*button_)(saw::ButtonEvent{(cycle_ / 20) % 2 == 0});
  }
  std::atomic<std::uint64_t> bad{0}, applied{0}, states{0}, homes{0};

 private:
  saw::Vec3 measured_{};
  std::uint64_t cycle_ = 0;
  saw::EventWrite<saw::ButtonEvent>* button_;
};

// A client task that reads, commands and observes the device through the bridge.
class Client : public saw::Task {
 public:
  explicit Client(std::string name = "client") : Task(std::move(name), saw::TaskConfig::periodic(1ms, 0)) {
    auto& r = require("arm");
    r.add_function("measured", measured_);
    r.add_function("servo_cf", servo_cf_);
    r.add_event_handler_write<saw::ButtonEvent>("button",
                                                [this](const saw::ButtonEvent&) { events.fetch_add(1); });
  }
  void run() override {
    saw::Vec3 p;
    if (measured_(p) == saw::Status::ok) reads.fetch_add(1);
    (void)servo_cf_(saw::Wrench{{0.1, 0, 0}, {}});
  }
  std::atomic<std::uint64_t> reads{0}, events{0};

 private:
  saw::FunctionRead<saw::Vec3> measured_;
  saw::FunctionWrite<saw::Wrench> servo_cf_;
};

// A served device, running; the segment is /saw.<name>.
struct Served {
  explicit Served(const char* what, ExportOptions o = {})
      : name(unique_name(what)), device(name), exporter(device, "arm", o) {
    manager.add(device);
    manager.start();
  }
  ~Served() { manager.stop(); }
  // The server keeps cycling: `n` more cycles happen (generous deadline; a dead server fails).
  bool keeps_cycling(std::uint64_t n = 50) {
    const auto c = device.statistics().cycles;
    return wait_for([&] { return device.statistics().cycles >= c + n; });
  }
  std::string name;
  Device device;
  Exporter exporter;
  saw::Manager manager;
};

// `client`'s "arm", connected through the bridge to the server exported as `server`.
void connect_through_bridge(saw::Manager& m, saw::Task& client, const std::string& server) {
  m.add_resolver(std::make_unique<ShmResolver>());
  m.add(client);
  m.connect(client.name(), "arm", server, "arm");
}

// The child's view of the segment, mapped writable from end to end: what a broken or hostile
// client could do. Layout comes from validation, as a client's would.
template <class F>
int as_hostile_client(const std::string& name, F f) {
  return in_child([&] {
    ShmSegment s = ShmSegment::attach("/saw." + name, /*writable=*/true);
    Layout l;
    if (!validate(s.data(), s.size(), &l).empty()) return 2;
    return f(SegmentView(s.data(), l), s);
  });
}

// Today's defect: the server re-read mirror_offset (and the slots' offsets and strides) from
// the segment every cycle, so one word from a client sent its next write 1 TB past the mapping.
TEST(BridgeTrust, AClientRewritingTheLayoutCannotMoveTheServersWrites) {
  Served s("tlay");
  Client early;
  saw::Manager m;
  connect_through_bridge(m, early, s.name);
  m.start();
  ASSERT_TRUE(wait_for([&] { return early.reads.load() > 20; }));
  EXPECT_EQ(as_hostile_client(s.name,
                              [](const SegmentView& v, ShmSegment&) {
                                auto& h = v.header();
                                // Every layout field at once (the old header's offsets lived here).
                                h.total_size = 1ULL << 40;
                                h.slot_count = 1'000'000;
                                h.mirror_words = 0x7FFFFFFF;
                                h.ring_capacity = 3;
                                h.command_slot_size = 0xFFFFFFF0U;
                                h.event_slot_size = 0x20;
                                h.manifest_count = 0xFFFFFFFFU;
                                return 0;
                              }),
            0);
  EXPECT_TRUE(s.keeps_cycling()) << "the server died or stopped";
  EXPECT_EQ(s.device.bad.load(), 0u);
  // The client attached before keeps its own copy of the layout: it still reads.
  const auto reads = early.reads.load();
  EXPECT_TRUE(wait_for([&] { return early.reads.load() > reads + 20; }));
  m.stop();
  // A new client is refused, with the reason.
  Client late("late");
  saw::Manager m2;
  m2.add_resolver(std::make_unique<ShmResolver>());
  m2.add(late);
  try {
    m2.connect("late", "arm", s.name, "arm");
    ADD_FAILURE() << "a corrupt segment was accepted";
  } catch (const saw::ConnectError& e) {
    EXPECT_NE(std::string(e.what()).find("refused"), std::string::npos) << e.what();
  }
}

// Records a client could write: an unknown index, NaN and out-of-limit forces, an enumerator
// out of range. None reaches the device; each is counted.
TEST(BridgeTrust, GarbageCommandsAreRefusedAndCountedNeverRun) {
  Served s("tcmd");
  const auto runs_before = s.exporter.commands_run();
  EXPECT_EQ(as_hostile_client(
                s.name,
                [](const SegmentView& v, ShmSegment&) {
                  const int slot = claim_slot(v, 5, getpid(), saw::monotonic_now());
                  if (slot < 0) return 3;
                  auto ring = command_ring(v, static_cast<std::uint32_t>(slot));
                  const auto push = [&](std::uint32_t index, const void* arg, std::size_t n) {
                    std::byte* r = ring.try_reserve();
                    if (r == nullptr) return false;
                    std::memcpy(r, &index, sizeof index);
                    std::memcpy(r + 16, arg, n);
                    ring.commit();
                    return true;
                  };
                  // Wire indices: 0 measured, 1 servo_cf, 2 state_command, 3 home, 4 twice.
                  const saw::Wrench nan{{std::nan(""), 0, 0}, {}};
                  const saw::Wrench inf{{0, -INFINITY, 0}, {}};
                  const saw::Wrench huge{{0, 0, 1e9}, {}};
                  const saw::Wrench ok{{1, 2, 3}, {}};
                  const std::uint8_t state = 77;
                  bool pushed = push(9999, &ok, sizeof ok) && push(0, &ok, sizeof ok) &&
                                push(4, &ok, sizeof ok) && push(1, &nan, sizeof nan) &&
                                push(1, &inf, sizeof inf) && push(1, &huge, sizeof huge) &&
                                push(2, &state, 1) && push(1, &ok, sizeof ok) && push(3, &ok, 0);
                  // Keep the slot beating until the server has drained it.
                  for (int i = 0; i < 200 && pushed; ++i) {
                    v.client_slot(static_cast<std::uint32_t>(slot)).heartbeat.store(saw::monotonic_now());
                    std::this_thread::sleep_for(1ms);
                  }
                  return pushed ? 0 : 4;
                }),
            0);
  ASSERT_TRUE(
      wait_for([&] { return s.exporter.commands_refused() + s.exporter.commands_run() >= runs_before + 9; }));
  EXPECT_EQ(s.exporter.commands_refused(), 7u)
      << "unknown index, a read, a query, NaN, inf, over the limit, bad enum";
  EXPECT_EQ(s.device.applied.load(), 1u) << "only the valid force";
  EXPECT_EQ(s.device.homes.load(), 1u);
  EXPECT_EQ(s.device.states.load(), 0u);
  EXPECT_EQ(s.device.bad.load(), 0u);
  EXPECT_TRUE(s.keeps_cycling());
}

// A head set a million records past the tail (or behind it) is not a ring's worth of work: the
// server drops it, counts it, and serves the next well-behaved client as before.
TEST(BridgeTrust, RingIndicesOutOfRangeAreDroppedAndCounted) {
  Served s("tring");
  EXPECT_EQ(as_hostile_client(s.name,
                              [](const SegmentView& v, ShmSegment&) {
                                const int slot = claim_slot(v, 6, getpid(), saw::monotonic_now());
                                if (slot < 0) return 3;
                                auto& c = v.client_slot(static_cast<std::uint32_t>(slot));
                                c.commands_head.store(c.commands_head.load() + (1ULL << 40));
                                c.events_tail.store(~0ULL);  // and a consumer index no consumer had
                                for (int i = 0; i < 100; ++i) {
                                  c.heartbeat.store(saw::monotonic_now());
                                  std::this_thread::sleep_for(1ms);
                                }
                                return 0;
                              }),
            0);
  EXPECT_GE(s.exporter.ring_errors(), 1u);
  EXPECT_EQ(s.exporter.commands_run(), 0u);
  EXPECT_EQ(s.device.bad.load(), 0u);
  Client good;
  saw::Manager m;
  connect_through_bridge(m, good, s.name);
  m.start();
  EXPECT_TRUE(wait_for([&] { return s.device.applied.load() > 20 && good.events.load() > 2; }))
      << "a well-behaved client is served after a broken one";
  m.stop();
}

// A client killed while it slept on the update bell left the server's sleeper count raised:
// one FUTEX_WAKE per cycle, forever. Its own slot's flag is cleared when its slot is freed.
TEST(BridgeTrust, AClientKilledAsleepLeavesNoWakeUpBehindAndItsSlotIsFreed) {
  Served s("tslp", ExportOptions{.slots = 2, .client_timeout = 200'000'000});
  // A real process (spawned, not forked: its proxy starts threads of its own).
  saw::testing::ChildProcess child({SAW_BRIDGE_PEER, "sleeper", s.name});
  ASSERT_GT(child.pid(), 0);
  Layout l;
  ShmSegment seg = ShmSegment::attach("/saw." + s.name, false);
  ASSERT_EQ(validate(seg.data(), seg.size(), &l), "");
  const SegmentView v(seg.data(), l);
  ASSERT_TRUE(wait_for([&] { return v.client_slot(0).update_waiting.load() == 1; }))
      << "the client never slept";
  child.kill9();
  ASSERT_TRUE(wait_for([&] { return s.exporter.slots_reclaimed() == 1; }))
      << "the dead client's slot stayed taken";
  EXPECT_EQ(v.client_slot(0).owner.load(), 0u);
  EXPECT_EQ(v.client_slot(0).update_waiting.load(), 0u) << "the server would wake a futex every cycle";
}

// A segment is never unlinked while its owner lives, whatever was written over its header: a
// peer that zeroed the magic word (as an owner that died during creation leaves it) once made the
// next server of that name take a live server's segment over.
TEST(BridgeTrust, ALiveServersSegmentIsNotTakenOverWhenItsHeaderIsScribbled) {
  Served s("town");
  ASSERT_EQ(as_hostile_client(s.name,
                              [](const SegmentView& v, ShmSegment&) {
                                v.header().magic = 0;
                                return 0;
                              }),
            0);
  Device second(s.name);
  try {
    Exporter e(second, "arm");
    ADD_FAILURE() << "a live server's segment was taken over";
  } catch (const BridgeError& e) {
    EXPECT_NE(std::string(e.what()).find("in use by a live process"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(s.keeps_cycling());
}

// Two client tasks in one process sharing one remote server's ring would be two producers on an
// SPSC ring. The second is refused at connect, with the reason; a reader may still connect.
TEST(BridgeTrust, TwoClientsInOneProcessCannotShareARemoteServersRings) {
  Served s("ttwo");
  Client a("a"), b("b");
  class Reader : public saw::Task {
   public:
    Reader() : Task("reader", saw::TaskConfig::periodic(1ms, 0)) {
      require("arm").add_function("measured", f_);
    }
    saw::FunctionRead<saw::Vec3> f_;
  } reader;
  saw::Manager m;
  m.add_resolver(std::make_unique<ShmResolver>());
  m.add(a);
  m.add(b);
  m.add(reader);
  m.connect("a", "arm", s.name, "arm");
  try {
    m.connect("b", "arm", s.name, "arm");
    ADD_FAILURE() << "two producers on one ring were accepted";
  } catch (const saw::ConnectError& e) {
    const std::string why = e.what();
    EXPECT_NE(why.find("another process"), std::string::npos) << why;
    EXPECT_NE(why.find("'a'"), std::string::npos) << why;
  }
  EXPECT_NO_THROW(m.connect("reader", "arm", s.name, "arm"));
}

// A server replaced by a segment this process cannot use (a ring capacity of 3 made SpscRing
// throw in the proxy's monitor thread: std::terminate of the RT client). Now: disconnected, and why.
TEST(BridgeTrust, AProxySurvivesABadReplacementSegmentAndSaysWhy) {
  const std::string name = unique_name("trepl");
  auto c = std::make_unique<Client>();
  saw::Manager m;
  m.add_resolver(std::make_unique<ShmResolver>());
  m.add(*c);
  Proxy* proxy = nullptr;
  {
    Served s("trepl");
    m.connect("client", "arm", s.name, "arm");
    proxy = dynamic_cast<Proxy*>(m.find(s.name));
    ASSERT_NE(proxy, nullptr);
    m.start();
    ASSERT_TRUE(wait_for([&] { return c->reads.load() > 10; }));
  }
  // A "server" whose header is sound but whose ring capacity is 3, beating as if alive.
  LayoutParams p;
  p.mirror_bytes = 32;
  p.slot_count = 2;
  p.ring_capacity = 4;
  Layout l;
  ASSERT_EQ(Layout::compute(p, l), "");
  ShmSegment fake = ShmSegment::create("/saw." + name, l.total_size, segment_owner_alive);
  const SegmentView v(fake.data(), l);
  initialize(v, name, "arm", 1, getpid());
  v.header().ring_capacity = 3;
  v.header().state.store(static_cast<std::uint32_t>(SegmentState::ready));
  const auto reads = c->reads.load();
  EXPECT_TRUE(wait_for([&] {
    v.header().heartbeat.store(saw::monotonic_now());
    return proxy->last_error().find("power of two") != std::string::npos;
  })) << proxy->last_error();
  EXPECT_FALSE(proxy->server_alive());
  EXPECT_LE(c->reads.load(), reads + 1) << "nothing is read from a segment that failed validation";
  EXPECT_TRUE(c->statistics().cycles > 0);
  m.stop();
}

// The black-box test of the issue: random 8-byte words at random offsets over a live server's
// whole segment, for 10 s, while a well-behaved client uses it. The server survives and keeps
// cycling, nothing invalid reaches the device, and the garbage it decoded was refused and counted.
TEST(BridgeTrust, TenSecondsOfRandomWritesOverTheWholeSegment) {
  Served s("tscr");
  Client good;
  saw::Manager m;
  connect_through_bridge(m, good, s.name);
  m.start();
  const auto cycles = s.device.statistics().cycles;
  std::uint64_t words = 0;
  const int status = in_child([&] {
    ShmSegment seg = ShmSegment::attach("/saw." + s.name, true);
    std::mt19937_64 rng(20261123);
    const auto end = std::chrono::steady_clock::now() + 10s;
    auto* base = static_cast<std::byte*>(seg.data());
    const std::size_t n = seg.size() / 8;
    while (std::chrono::steady_clock::now() < end) {
      for (int k = 0; k < 20; ++k) {
        const std::uint64_t w = rng();
        // Half the words land in the client region (slots, rings), where they are most likely decoded.
        std::size_t at = rng() % n;
        if (k % 2 == 0) at = (seg.size() / 2 + rng() % (seg.size() / 2)) / 8;
        std::memcpy(base + at * 8, &w, 8);
      }
      std::this_thread::sleep_for(1ms);
    }
    return 0;
  });
  words = 10 * 1000 * 20;
  EXPECT_EQ(status, 0);
  EXPECT_TRUE(s.keeps_cycling()) << "the server stopped";
  const auto ran = s.device.statistics().cycles - cycles;
  std::printf(
      "scribble: ~%llu words in 10 s; server cycles %llu; commands run %llu, refused %llu; ring errors "
      "%llu; queries refused %llu; client reads %llu\n",
      static_cast<unsigned long long>(words), static_cast<unsigned long long>(ran),
      static_cast<unsigned long long>(s.exporter.commands_run()),
      static_cast<unsigned long long>(s.exporter.commands_refused()),
      static_cast<unsigned long long>(s.exporter.ring_errors()),
      static_cast<unsigned long long>(s.exporter.queries_refused()),
      static_cast<unsigned long long>(good.reads.load()));
  EXPECT_GT(ran, 1000u) << "a 1 kHz task ran fewer than 1,000 cycles in 10 s";
  EXPECT_EQ(s.device.bad.load(), 0u) << "an invalid command reached the device";
  EXPECT_GT(s.exporter.commands_refused() + s.exporter.ring_errors(), 0u) << "no garbage was decoded at all?";
  m.stop();
}

}  // namespace
