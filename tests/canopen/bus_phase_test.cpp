// The two phases of a canopen_bus's period, run by the manager (stepped): a client's answer to a
// drive's TPDO goes out before the next SYNC, as that of an arm that owns its bus.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "saw/can/virtual_bus.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/canopen/canopen_bus.hpp"
#include "saw/manager.hpp"
#include "shared_rig.hpp"

namespace saw::canopen::test {
namespace {

using std::chrono::microseconds;
using std::chrono::milliseconds;

// The drives, stepped at the end of each period (after the SYNC: their TPDOs for the next), and a
// spy that keeps every frame on the bus in the order the bus carried it.
class NodesTask final : public Task {
 public:
  NodesTask(RingNetwork& network, Drives& drives, std::vector<RingPort*> stamped)
      : Task("nodes", with_offset(microseconds(900))),
        drives_(drives),
        spy_(network.attach("spy")),
        stamped_(std::move(stamped)) {}
  void run() override {
    drives_.step(now());
    for (RingPort* p : stamped_) p->now = now() + ms;  // the next period's frames
    can::Received r[64];
    for (std::size_t n; (n = spy_.receive(r)) > 0;)
      for (std::size_t i = 0; i < n; ++i) frames.push_back(r[i].frame);
  }
  static TaskConfig with_offset(microseconds offset) {
    TaskConfig t = TaskConfig::periodic(milliseconds(1), 0);
    t.offset = offset;
    return t;
  }
  std::vector<can::Frame> frames;

 private:
  Drives& drives_;
  RingPort& spy_;
  std::vector<RingPort*> stamped_;
};

// Node 1's first TPDO1 that shows "ready to switch on" (its statusword), then the first RPDO1
// after it whose controlword is "switch on", which the arm computes from it: the SYNCs between
// the two on the bus. Empty if either is missing.
std::optional<int> syncs_from_state_to_answer(const std::vector<can::Frame>& frames) {
  std::optional<int> syncs;
  for (const can::Frame& f : frames) {
    const std::uint32_t id = f.can_id() & CAN_SFF_MASK;
    const unsigned word = f.len >= 2 ? unsigned{f.data[0]} | unsigned{f.data[1]} << 8 : 0u;
    if (!syncs) {
      if (id == 0x181 && (word & 0x6F) == 0x21) syncs = 0;
      continue;
    }
    if (id == 0x080) ++*syncs;
    if (id == 0x201 && (word & 0x8F) == 0x07) return syncs;
  }
  return std::nullopt;
}

struct Clock {
  TimeNs now = 0;
};

// Runs the manager stepped from t0 = 1 s (the start-ups before it on their own clock) for 200 ms.
std::vector<can::Frame> run(Manager& m, NodesTask& nodes) {
  m.start_stepped(1'000'000'000);
  m.step_until(1'199'999'999);
  m.stop();
  return nodes.frames;
}

TEST(CanopenBusPhases, AClientAnswersADrivesTpdoBeforeTheNextSyncAsAnArmOwningItsBus) {
  // The arm that owns its bus: it reads, computes, sends its RPDOs, then SYNC, in its cycle.
  std::optional<int> owned;
  {
    RingNetwork network;
    RingPort& port = network.attach("arm bus");
    Drives drives{network, {}};
    drives.add(network, {1, 2});
    CanopenArmConfig c = client("test", {1, 2});
    Clock clock;
    c.startup_pause = [&] {
      drives.step(clock.now);
      clock.now += ms;
      port.now = clock.now;
      return clock.now;
    };
    Manager m;
    m.add(std::make_unique<CanopenArm>("arm", TaskConfig::periodic(milliseconds(1), 0), c, port));
    auto& nodes =
        static_cast<NodesTask&>(m.add(std::make_unique<NodesTask>(network, drives, std::vector{&port})));
    owned = syncs_from_state_to_answer(run(m, nodes));
    EXPECT_EQ(m.find("arm") != nullptr ? static_cast<CanopenArm*>(m.find("arm"))->operating_state().state
                                       : OperatingStateValue::fault,
              OperatingStateValue::enabled);
  }
  // The same arm as a client of a canopen_bus: route phase, the arm, send phase.
  std::optional<int> shared;
  {
    RingNetwork network;
    RingPort& port = network.attach("shared");
    Drives drives{network, {}};
    drives.add(network, {1, 2});
    CanopenBusConfig b;
    b.uri = "test:phases";
    b.heartbeat_period = 10 * ms;
    b.heartbeat_timeout = 50 * ms;
    Manager m;
    auto& bus = static_cast<CanopenBus&>(m.add(std::make_unique<CanopenBus>(
        "phases-bus", TaskConfig::periodic(milliseconds(1), 0), b, std::make_unique<Borrowed>(port))));
    EXPECT_EQ(bus.sync_task().config().offset, microseconds(500)) << "the default: half the period";
    EXPECT_EQ(m.find("phases-bus_sync"), &bus.sync_task()) << "the manager runs the send phase too";
    CanopenArmConfig c = client("phases-bus", {1, 2});
    Clock clock;
    c.startup_pause = [&] {
      drives.step(clock.now);
      clock.now += ms;
      port.now = clock.now;
      return clock.now;
    };
    auto& arm = static_cast<CanopenArm&>(
        m.add(std::make_unique<CanopenArm>("arm", TaskConfig::periodic(milliseconds(1), 0), c)));
    EXPECT_EQ(arm.config().offset, microseconds(250)) << "none given: between the two phases";
    auto& nodes =
        static_cast<NodesTask&>(m.add(std::make_unique<NodesTask>(network, drives, std::vector{&port})));
    const std::vector<can::Frame> frames = run(m, nodes);
    shared = syncs_from_state_to_answer(frames);
    EXPECT_EQ(arm.operating_state().state, OperatingStateValue::enabled);
    const BusTaskCounters k = bus.bus_task().counters();
    EXPECT_EQ(k.syncs, 200u);
    EXPECT_EQ(k.phase_skips, 0u);
    // Each period on the bus: the arm's two RPDOs, then SYNC (the heartbeat may follow it).
    int periods_checked = 0;
    for (std::size_t i = 2; i < frames.size(); ++i) {
      if ((frames[i].can_id() & CAN_SFF_MASK) != 0x080 || i < 40) continue;
      EXPECT_EQ(frames[i - 2].can_id() & CAN_SFF_MASK, 0x201u) << "frame " << i;
      EXPECT_EQ(frames[i - 1].can_id() & CAN_SFF_MASK, 0x202u) << "frame " << i;
      ++periods_checked;
    }
    EXPECT_GT(periods_checked, 100);
  }
  ASSERT_TRUE(owned.has_value());
  ASSERT_TRUE(shared.has_value());
  EXPECT_EQ(*owned, 0) << "the answer before the next SYNC: one period from sample to actuation";
  EXPECT_EQ(*shared, *owned) << "a client of a canopen_bus as fast as an arm that owns its bus";
}

TEST(CanopenBusPhases, AClientOffsetOutsideTheTwoPhasesIsRefusedNamingBoth) {
  RingNetwork network;
  RingPort& port = network.attach("shared");
  CanopenBusConfig b;
  b.uri = "test:phases-refused";
  b.sync_offset = 600'000;
  TaskConfig t = TaskConfig::periodic(milliseconds(1), 0);
  t.offset = microseconds(100);
  CanopenBus bus("phases-bus", t, b, std::make_unique<Borrowed>(port));
  EXPECT_EQ(bus.sync_task().config().offset, microseconds(600));
  for (const int us : {50, 100, 600, 900}) {
    TaskConfig c = TaskConfig::periodic(milliseconds(1), 0);
    c.offset = microseconds(us);
    std::string what = "not refused";
    try {
      (void)client_task("phases-bus", "arm", c);
    } catch (const std::runtime_error& e) {
      what = e.what();
    }
    EXPECT_EQ(what,
              "'arm' runs at offset " + std::to_string(us) +
                  " us in the period, its bus task 'phases-bus' routes the frames received at 100 us and "
                  "sends SYNC at 600 us: a client of a canopen_bus runs between the two (an offset above "
                  "100 us and below 600 us, or none: the middle)");
  }
  TaskConfig inside = TaskConfig::periodic(milliseconds(1), 0);
  inside.offset = microseconds(101);
  EXPECT_EQ(client_task("phases-bus", "arm", inside).offset, microseconds(101));
  inside.offset = {};
  EXPECT_EQ(client_task("phases-bus", "arm", inside).offset, microseconds(350));
}

// A bus whose receive() first runs a hook: the other phase arriving while route() reads.
class Hooked final : public can::Bus {
 public:
  explicit Hooked(can::Bus& b) : b_(b) {}
  std::size_t receive(std::span<can::Received> out) noexcept override {
    if (on_receive) on_receive();
    return b_.receive(out);
  }
  std::size_t send(std::span<const can::Frame> f) noexcept override { return b_.send(f); }
  can::BusState state() const noexcept override { return b_.state(); }
  can::BusCounters counters() const noexcept override { return b_.counters(); }
  const std::string& name() const noexcept override { return b_.name(); }
  std::function<void()> on_receive;

 private:
  can::Bus& b_;
};

// The route and send phases never run at once: one that finds the other running skips its
// turn, and says so, without waiting; the next turn runs.
TEST(CanopenBusPhases, APhaseThatMeetsTheOtherSkipsAndCountsIt) {
  RingNetwork network;
  RingPort& port = network.attach("shared");
  RingPort& spy = network.attach("spy");
  auto hooked = std::make_unique<Hooked>(port);
  Hooked& hook = *hooked;
  BusTaskConfig k;
  k.route_offset = 0;
  k.send_offset = 500'000;
  BusTask task(std::move(hooked), k);
  int sends_refused = 0;
  hook.on_receive = [&] { sends_refused += task.send(500'000) ? 0 : 1; };
  EXPECT_TRUE(task.route(0));
  EXPECT_EQ(sends_refused, 1);
  EXPECT_EQ(task.counters().phase_skips, 1u);
  EXPECT_EQ(task.counters().syncs, 0u) << "the skipped send sent nothing";
  hook.on_receive = {};
  EXPECT_TRUE(task.send(500'000));
  EXPECT_EQ(task.counters().syncs, 1u);
  can::Received r[8];
  std::size_t syncs = 0;
  for (std::size_t n; (n = spy.receive(r)) > 0;)
    for (std::size_t i = 0; i < n; ++i) syncs += (r[i].frame.can_id() & CAN_SFF_MASK) == 0x080;
  EXPECT_EQ(syncs, 1u);
}

// Both phases in their own threads (the manager's, real time): each period's SYNC on the bus,
// and what the two threads share handed over through the flag (ThreadSanitizer checks it).
TEST(CanopenBusPhases, BothPhasesRunInTheirOwnThreadsOnTheVirtualBus) {
  const std::string name = "phases-" + std::to_string(::getpid());
  CanopenBusConfig b;
  b.uri = "virtual:" + name;
  b.heartbeat_period = 10 * ms;
  b.heartbeat_timeout = 50 * ms;
  std::uint64_t seen = 0;
  {
    Manager m;
    auto& bus = static_cast<CanopenBus&>(
        m.add(std::make_unique<CanopenBus>("threads-bus", TaskConfig::periodic(milliseconds(1), 0), b)));
    can::BusConfig c;
    c.uri = b.uri;
    const auto spy = can::open_bus(c);
    m.start();
    // Until 50 SYNCs went by (bounded: a machine too loaded to give 50 periods in 20 s fails).
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    can::Received r[64];
    while (seen < 50 && std::chrono::steady_clock::now() < give_up) {
      const std::size_t n = spy->receive(r);
      for (std::size_t i = 0; i < n; ++i) seen += (r[i].frame.can_id() & CAN_SFF_MASK) == 0x080;
      if (n == 0) std::this_thread::sleep_for(milliseconds(1));
    }
    m.stop();
    const BusTaskCounters k = bus.bus_task().counters();
    EXPECT_GE(k.syncs, seen);
    EXPECT_EQ(k.frames_sent, k.syncs + k.heartbeats) << "no client: SYNC and the heartbeat only";
    // Not one route per SYNC: a thread that wakes late skips periods to keep its phase (the
    // route thread's count and the send thread's differ on a loaded machine).
    EXPECT_GT(k.cycles, 0u) << "the route phase ran in its own thread";
  }
  (void)can::remove_virtual_bus(name);
  EXPECT_GE(seen, 50u);
}

}  // namespace
}  // namespace saw::canopen::test
