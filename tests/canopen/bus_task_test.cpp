// Two CANopen components on one bus task, against in-process drives on an in-memory bus.
#include "saw/canopen/bus_task.hpp"

#include <gtest/gtest.h>

#include <functional>
#include <memory>
#include <stdexcept>

#include "saw/canopen/canopen_arm.hpp"
#include "saw/detail/access.hpp"
#include "saw/log.hpp"
#include "shared_rig.hpp"

namespace saw::canopen::test {
namespace {

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
  EXPECT_THROW(CanopenArm("lost", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c),
               std::runtime_error);
}

// Each SYNC applies the RPDOs of the period before it: a client at another period than the bus
// task's is refused when it joins, naming both and both periods; nothing of it is attached.
TEST(CanopenBusTask, RefusesAClientWhosePeriodIsNotTheBusTasks) {
  SharedRig rig;
  const auto refusal = [](const std::function<void()>& make) -> std::string {
    try {
      make();
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "not refused";
  };
  EXPECT_EQ(
      refusal([&] {
        (void)CanopenArm("slow", TaskConfig::periodic(std::chrono::milliseconds(2), 0),
                         client(rig.name, {1}));
      }),
      "'slow' runs every 2 ms, its bus task 'shared-test-bus' every 1 ms: a client of a canopen_bus must "
      "have the bus task's period");
  EXPECT_EQ(
      refusal([&] {
        (void)CanopenIo("fast", TaskConfig::periodic(std::chrono::microseconds(500), 0),
                        gripper_config(rig.name, 10));
      }),
      "'fast' runs every 500 us, its bus task 'shared-test-bus' every 1 ms: a client of a canopen_bus must "
      "have the bus task's period");
  EXPECT_EQ(rig.task->clients(), 0u);
  // The same clients at the bus task's period join it.
  auto arm = rig.make("arm", {1});
  auto io = rig.make_io("gripper", 10);
  EXPECT_EQ(rig.task->clients(), 2u);
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

namespace saw::canopen::test {
namespace {

TEST(CanopenBusTask, AnArmAndAGripperIoNodeShareTheBusAndFaultAlone) {
  SharedRig rig;
  auto arm = rig.make("arm", {1, 2});
  auto gripper = rig.make_io("gripper", 10);
  Client client(*gripper);
  arm->startup();
  gripper->startup();
  EXPECT_EQ(rig.io_node->state, 0x05) << "configured and started";
  rig.cycle({arm.get(), gripper.get()}, 60);
  ASSERT_EQ(arm->operating_state().state, OperatingStateValue::enabled);
  ASSERT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  // Not commanded yet: the jaw's safe opening (0.02 m, 2000 counts) goes out, and is measured.
  EXPECT_EQ(rig.io_node->output, 2000);
  EXPECT_NEAR(gripper->measured_js().position[0], 0.02, 1e-9);
  // servo_jp to 0.03 m: 3000 counts in RPDO1, the input follows (50 counts per SYNC).
  for (int i = 0; i < 40; ++i) {
    client.jp(0.02 + 0.00025 * std::min(i, 40));
    rig.cycle({arm.get(), gripper.get()});
  }
  rig.cycle({arm.get(), gripper.get()}, 10);
  EXPECT_EQ(rig.io_node->output, 2975);
  EXPECT_NEAR(gripper->measured_js().position[0], 0.02975, 1e-9);
  // A runtime SDO upload through the gripper's queue (the cycle runs it); one for a node not its own is
  // refused.
  SdoRequest q;
  q.node = 10;
  q.index = 0x1000;
  q.tag = 7;
  ASSERT_EQ(gripper->node().sdo_queue().submit(q), Status::ok);
  q.node = 3;
  q.tag = 8;
  ASSERT_EQ(gripper->node().sdo_queue().submit(q), Status::ok);
  rig.cycle({arm.get(), gripper.get()}, 10);
  SdoReply r1, r2;
  ASSERT_TRUE(gripper->node().sdo_queue().take_reply(r1));
  ASSERT_TRUE(gripper->node().sdo_queue().take_reply(r2));
  EXPECT_TRUE(r1.ok());
  EXPECT_EQ(r1.tag, 7u);
  EXPECT_EQ(r1.size, 4u);
  EXPECT_EQ(r1.data[0], 0x91);
  EXPECT_EQ(r1.data[2], 0x0C);
  EXPECT_EQ(r2.tag, 8u);
  EXPECT_EQ(r2.status, Status::invalid);
  // The node's heartbeat and TPDOs stop: the gripper faults, the arm goes on.
  rig.io_node->silent = true;
  rig.cycle({arm.get(), gripper.get()}, 60);
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(arm->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig.io_node->output, 2000) << "its safe output at the fault";
  // The node reboots: the gripper faults (node rebooted); the next enable configures it again
  // from the cycle (SDO, NMT start) and it runs again, the arm enabled throughout.
  rig.io_node->silent = false;
  rig.cycle({arm.get(), gripper.get()}, 20);  // its heartbeat back first: an enable before faults again
  client.command(StateCommand::enable);
  rig.cycle({arm.get(), gripper.get()}, 30);
  ASSERT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  rig.io_node->reboot();
  rig.cycle({arm.get(), gripper.get()}, 5);
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(gripper->device_status().reason_text(), "node rebooted");
  EXPECT_FALSE(rig.io_node->configured);
  client.command(StateCommand::enable);
  rig.cycle({arm.get(), gripper.get()}, 100);
  EXPECT_TRUE(rig.io_node->configured);
  EXPECT_EQ(rig.io_node->state, 0x05);
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(arm->operating_state().state, OperatingStateValue::enabled);
  // At exit: the safe output, a SYNC and NMT pre-operational for the node.
  rig.keep = false;
  (void)drain(rig.spy);
  gripper->cleanup();
  arm->cleanup();
  const auto last = drain(rig.spy);
  bool safe = false, pre_op = false;
  for (const can::Frame& f : last) {
    if ((f.can_id() & CAN_SFF_MASK) == 0x20A && !pre_op) safe = f.data[0] == 0xD0 && f.data[1] == 0x07;
    if (f.can_id() == 0 && f.len == 2 && f.data[0] == 0x80 && f.data[1] == 10) pre_op = true;
  }
  EXPECT_TRUE(safe && pre_op);
}

}  // namespace
}  // namespace saw::canopen::test

namespace saw::canopen::test {
namespace {

// A later client's start-up reads the bus itself (no thread cycles yet): an EMCY of an earlier
// client's node sent meanwhile goes to that client, whose first cycle reports it, instead of
// being read and dropped by the other component's start-up.
TEST(CanopenBusTask, AnEmcyOfAnEarlierClientsNodeDuringALaterClientsStartUpReachesIt) {
  SharedRig rig;
  auto gripper = rig.make_io("gripper", 10);
  auto arm = rig.make("arm", {1, 2});
  gripper->startup();
  int pauses = 0;
  rig.during_startup = [&] {
    if (++pauses == 5)  // the arm's nodes reset, their boot-ups awaited
      rig.io_node->send(0x80 + 10, {0x00, 0x50, 0x81, 0, 0, 0, 0, 0});  // 0x5000 device hardware
  };
  arm->startup();
  ASSERT_GT(pauses, 5);
  rig.during_startup = nullptr;
  EXPECT_EQ(rig.task->counters().dropped, 0u);
  rig.cycle({arm.get(), gripper.get()}, 30);
  EXPECT_EQ(gripper->status().emcy, 1u);
  EXPECT_EQ(gripper->status().last_emcy, 0x5000);
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(gripper->device_status().reason_text(), "emergency message");
  EXPECT_EQ(arm->operating_state().state, OperatingStateValue::enabled) << "the EMCY is the gripper's alone";
  EXPECT_EQ(arm->status().emcy, 0u);
}

// More frames for an earlier client during a start-up than its in-ring holds: the rest are
// counted dropped (the bus task's and the client's port's figures), none is lost silently.
TEST(CanopenBusTask, FramesForAnEarlierClientBeyondItsRingDuringAStartUpAreCountedDropped) {
  SharedRig rig;
  auto gripper = rig.make_io("gripper", 10);
  auto arm = rig.make("arm", {1});
  gripper->startup();
  constexpr int sent = 600;  // the ring holds 512
  bool once = false;
  rig.during_startup = [&] {
    if (once) return;
    once = true;
    for (int i = 0; i < sent; ++i) rig.io_node->send(0x80 + 10, {0x10, 0x23, 0x02, 0, 0, 0, 0, 0});
  };
  arm->startup();
  rig.during_startup = nullptr;
  const std::uint64_t dropped = rig.task->counters().dropped;
  EXPECT_EQ(dropped, static_cast<std::uint64_t>(sent - 512));
  EXPECT_EQ(rig.task->port(0).dropped(), dropped);
  rig.cycle({arm.get(), gripper.get()}, 30);
  EXPECT_EQ(gripper->status().emcy + dropped, static_cast<std::uint64_t>(sent));
  EXPECT_EQ(arm->operating_state().state, OperatingStateValue::enabled);
}

}  // namespace
}  // namespace saw::canopen::test

namespace saw::canopen::test {
namespace {

// The I/O node reboots again while the enable configures it after a first reboot: what was
// written before is gone, so the configuration starts over (every download again), and the log
// says that it rebooted (an enable under way shows no FAULT for it).
TEST(CanopenBusTask, AnIoNodeThatRebootsWhileItIsConfiguredAgainGetsItAllAgainAndItIsLogged) {
  saw::LogRecord r;
  while (saw::log_ring().pop(r)) {
  }
  SharedRig rig;
  auto gripper = rig.make_io("gripper", 10);
  Client client(*gripper);
  gripper->startup();
  const int full = rig.io_node->downloads;
  ASSERT_GT(full, 3);
  rig.cycle({gripper.get()}, 30);
  ASSERT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  rig.io_node->reboot();
  rig.cycle({gripper.get()}, 5);
  ASSERT_EQ(gripper->operating_state().state, OperatingStateValue::fault);
  client.command(StateCommand::enable);
  for (int i = 0; i < 50 && rig.io_node->downloads < 2; ++i) rig.cycle({gripper.get()});
  ASSERT_TRUE(gripper->enabling());
  ASSERT_LT(rig.io_node->downloads, full) << "rebooted again in the middle of its configuration";
  rig.io_node->reboot();
  for (int i = 0; i < 500 && gripper->operating_state().state != OperatingStateValue::enabled; ++i)
    rig.cycle({gripper.get()});
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(rig.io_node->downloads, full) << "every start-up write after the second reboot";
  EXPECT_EQ(rig.io_node->state, 0x05);
  bool logged = false;
  while (saw::log_ring().pop(r))
    logged = logged || saw::format_log_record(r).find(
                           "node 10 rebooted (boot-up seen) during the enable: "
                           "configuring it again") != std::string::npos;
  EXPECT_TRUE(logged);
}

}  // namespace
}  // namespace saw::canopen::test
