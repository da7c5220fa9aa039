// Two CANopen components on one bus task, against in-process drives on an in-memory bus.
#include <gtest/gtest.h>

#include <memory>
#include <stdexcept>

#include "arm_rig.hpp"
#include "saw/canopen/bus_task.hpp"
#include "saw/canopen/canopen_arm.hpp"
#include "saw/detail/access.hpp"

namespace saw::canopen::test {
namespace {

// The bus task owns its bus; the network owns the test's ports: a bus that forwards to one.
class Borrowed final : public can::Bus {
 public:
  explicit Borrowed(can::Bus& b) : b_(b) {}
  std::size_t receive(std::span<can::Received> out) noexcept override { return b_.receive(out); }
  std::size_t send(std::span<const can::Frame> f) noexcept override { return b_.send(f); }
  can::BusState state() const noexcept override { return b_.state(); }
  can::BusCounters counters() const noexcept override { return b_.counters(); }
  const std::string& name() const noexcept override { return b_.name(); }

 private:
  can::Bus& b_;
};

CanopenArmConfig client(const std::string& bus, std::vector<std::uint8_t> nodes) {
  CanopenArmConfig c = arm_config(cia402::csp, nodes.size());
  c.bus = bus;
  c.chain.reset();
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    c.joints[i].node = nodes[i];
    c.joints[i].name = "n" + std::to_string(nodes[i]);
  }
  c.start_enabled = true;
  c.feedback_timeout = 20 * ms;
  return c;
}

struct SharedRig {
  SharedRig() : bus_port(network.attach("shared")), spy(network.attach("spy")) {
    BusTaskConfig k;
    k.heartbeat_period = 10 * ms;
    k.heartbeat_timeout = 50 * ms;
    task = std::make_shared<BusTask>(std::make_unique<Borrowed>(bus_port), k);
    publish_bus_task(name, task);
    for (const int node : {1, 2, 3}) {
      TestDriveConfig d;
      d.node = static_cast<std::uint8_t>(node);
      drives.list.push_back(std::make_unique<TestDrive>(network, d));
    }
  }
  ~SharedRig() { withdraw_bus_task(name); }
  std::unique_ptr<CanopenArm> make(const std::string& who, std::vector<std::uint8_t> nodes) {
    CanopenArmConfig c = client(name, std::move(nodes));
    c.startup_pause = [this] {
      drives.step(now);
      now += ms;
      bus_port.now = now;
      return now;
    };
    auto arm = std::make_unique<CanopenArm>(who, TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
    arm->state_table().finalize();
    return arm;
  }
  // One period: the bus task, then its clients, then the drives (their TPDOs for the next).
  void cycle(std::initializer_list<CanopenArm*> arms, int n = 1) {
    for (int i = 0; i < n; ++i) {
      bus_port.now = now;
      task->cycle(now);
      for (CanopenArm* a : arms) detail::Access::step(*a, now);
      drives.step(now);
      now += ms;
      can::Received r[64];
      for (std::size_t k; (k = spy.receive(r)) > 0;)
        for (std::size_t j = 0; j < k; ++j) seen.push_back(r[j].frame);
    }
  }

  std::vector<can::Frame> seen;  // every frame on the bus during cycle()
  const std::string name = "shared-test-bus";
  RingNetwork network;
  RingPort& bus_port;
  RingPort& spy;
  Drives drives{network, {}};
  std::shared_ptr<BusTask> task;
  TimeNs now = 0;
};

std::vector<can::Frame> drain(RingPort& p) {
  std::vector<can::Frame> out;
  can::Received r[64];
  for (std::size_t n; (n = p.receive(r)) > 0;)
    for (std::size_t i = 0; i < n; ++i) out.push_back(r[i].frame);
  return out;
}

TEST(CanopenBusTask, TwoComponentsShareOneBusAndOneSync) {
  SharedRig rig;
  auto left = rig.make("left", {1, 2});
  auto right = rig.make("right", {3});
  ASSERT_NE(left->port(), nullptr);
  // Each configured its own nodes with the bus task's heartbeat (node 127, its 50 ms).
  left->startup();
  right->startup();
  for (std::size_t i = 0; i < 3; ++i) {
    bool consumer = false;
    for (const TestDrive::Write& w : rig.drives[i].writes())
      if (w.address == ObjectAddress{0x1016, 1}) consumer = w.value == (127u << 16 | 50u);
    EXPECT_TRUE(consumer) << "node " << i + 1;
  }
  (void)drain(rig.spy);
  rig.cycle({left.get(), right.get()}, 100);
  const auto frames = rig.seen;
  EXPECT_EQ(left->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(right->operating_state().state, OperatingStateValue::enabled);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(rig.drives[i].state(), cia402::State::operation_enabled);
  // One SYNC per bus cycle, the bus task's alone; each cycle's RPDOs before its SYNC.
  std::size_t syncs = 0, heartbeats = 0;
  bool rpdo_since_sync[3] = {};
  std::size_t late = 0, after_sync = 0;
  std::uint32_t previous = 0;
  for (const can::Frame& f : frames) {
    const std::uint32_t id = f.can_id() & CAN_SFF_MASK;
    if (id == 0x080) {
      ++syncs;
      for (bool& seen : rpdo_since_sync) {
        if (syncs > 5 && !seen) ++late;
        seen = false;
      }
    }
    if (id >= 0x201 && id <= 0x203) {
      rpdo_since_sync[id - 0x201] = true;
      if (previous == 0x080) ++after_sync;  // an RPDO the SYNC just sent does not apply
    }
    if (id != 0x700 + 127) previous = id;
    if (id == 0x700 + 127) ++heartbeats;
  }
  EXPECT_EQ(syncs, 100u);
  EXPECT_EQ(late, 0u) << "a SYNC without every drive's RPDO before it";
  EXPECT_EQ(after_sync, 0u) << "RPDOs sent after the SYNC of their cycle";
  EXPECT_GE(heartbeats, 9u);
  EXPECT_EQ(left->master().counters().syncs, 0u);
  EXPECT_EQ(rig.task->counters().foreign_frames, 0u);
  EXPECT_EQ(rig.task->counters().dropped, 0u);

  // A fault of right's drive is right's: left stays enabled.
  rig.drives[2].raise_fault(0x2310);
  rig.cycle({left.get(), right.get()}, 20);
  EXPECT_EQ(right->operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(right->fault_reason(), FaultReason::emcy);
  EXPECT_EQ(left->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig.drives[0].state(), cia402::State::operation_enabled);

  // The end: every node of every client disabled and pre-operational.
  (void)drain(rig.spy);
  left->cleanup();
  right->cleanup();
  const auto last = drain(rig.spy);
  for (const int node : {1, 2, 3}) {
    bool disabled = false, pre_op = false;
    for (const can::Frame& f : last) {
      if ((f.can_id() & CAN_SFF_MASK) == 0x200u + static_cast<unsigned>(node) && !pre_op)
        disabled = f.data[0] == 0 && f.data[1] == 0;
      if (f.can_id() == 0 && f.len == 2 && f.data[0] == 0x80 && f.data[1] == node) pre_op = true;
    }
    EXPECT_TRUE(disabled && pre_op) << "node " << node;
  }
}

TEST(CanopenBusTask, RefusesANodeOrIdentifierTakenAndTheMastersOwnNode) {
  SharedRig rig;
  auto left = rig.make("left", {1, 2});
  try {
    (void)rig.make("other", {2});
    FAIL() << "node 2 twice";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'left''s already"), std::string::npos) << e.what();
  }
  const std::uint8_t master[] = {127};
  EXPECT_THROW((void)rig.task->attach("x", master, {}), std::invalid_argument);
  // A bus that is no canopen_bus of this process.
  CanopenArmConfig c = client("no-such-bus", {5});
  EXPECT_THROW(CanopenArm("lost", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c), std::runtime_error);
}

TEST(CanopenBusTask, NodesOfAClientThatNeverShutThemDownGoPreOperationalWithTheBusTask) {
  auto rig = std::make_unique<SharedRig>();
  const std::uint8_t nodes[] = {9};
  (void)rig->task->attach("never ran", nodes, {});
  RingPort& spy = rig->spy;
  rig->task.reset();  // the last holder: the bus task ends
  const auto last = drain(spy);
  ASSERT_EQ(last.size(), 1u);
  EXPECT_EQ(last[0].data[0], 0x80);
  EXPECT_EQ(last[0].data[1], 9);
}

}  // namespace
}  // namespace saw::canopen::test
