// A shared bus's cycle (the bus task routing frames to its clients, an arm of two CiA 402 drives and
// a gripper's I/O node each on its port, faults of each and their recovery, the I/O node rebooted
// and configured again from the cycle (rebooting once more meanwhile), its runtime SDO) allocates, locks,
// waits and prints nothing: checked by the RT guard on every cycle, the in-process nodes included.
#include <gtest/gtest.h>

#include "guard_support.hpp"
#include "saw/canopen/canopen_bus.hpp"
#include "saw/manager.hpp"
#include "saw/rt_context.hpp"
#include "shared_rig.hpp"

namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;
using saw::OperatingStateValue;
using saw::StateCommand;

TEST(RtGuard, CanopenBusTaskWithAnArmAndAnIoNodeIsRtClean) {
  saw::testing::GuardWindow window;
  SharedRig rig;  // set-up and start-up: not RT
  auto arm = rig.make("arm", {1, 2});
  auto gripper = rig.make_io("gripper", 10);
  Client client(*gripper);
  arm->startup();
  gripper->startup();
  rig.keep = false;  // the spy's frames are not kept (a vector would grow in the cycle)

  constexpr int cycles = 3000;
  int both_enabled = 0, gripper_faults = 0, sdo_ok = 0;
  bool rebooted_enabling = false;
  OperatingStateValue previous = OperatingStateValue::disabled;
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("canopen shared bus");
      if (i >= 100) client.jp(0.02 + 0.01 * ((i / 500) % 2));
      if (i == 600) rig.drives[1].raise_fault(0x2310);  // the arm's: the gripper goes on
      if (i == 700) rig.drives[1].clear_fault();
      if (i == 1200) rig.io_node->silent = true;  // the gripper's: the arm goes on
      if (i == 1300) rig.io_node->silent = false;
      if (i == 1400) client.command(StateCommand::enable);
      if (i == 1450) {  // a warning of node 10 (CAN error passive): logged, no FAULT
        const std::uint8_t emcy[] = {0x20, 0x81, 0x11, 0, 0, 0, 0, 0};
        const saw::can::Frame f = saw::can::classic(0x8A, emcy);
        (void)rig.io_node->port.send(std::span(&f, 1));
      }
      if (i == 1500) {
        const std::uint8_t emcy[] = {0x00, 0x50, 0x81, 0, 0, 0, 0, 0};  // an error EMCY of node 10
        const saw::can::Frame f = saw::can::classic(0x8A, emcy);
        (void)rig.io_node->port.send(std::span(&f, 1));
      }
      if (i == 1600) client.command(StateCommand::enable);
      if (i == 2000) rig.io_node->reboot();  // configured again by the next enable, from the cycle
      if (i == 2100) client.command(StateCommand::enable);
      if (i == 2102) {  // again, while that enable configures it: the configuration starts over
        rebooted_enabling = gripper->enabling();
        rig.io_node->reboot();
      }
      if (i % 200 == 100) {  // a runtime SDO upload of the I/O node's device type
        SdoRequest q;
        q.node = 10;
        q.index = 0x1000;
        (void)gripper->node().sdo_queue().submit(q);
      }
      for (SdoReply r; gripper->node().sdo_queue().take_reply(r);) sdo_ok += r.ok();
      rig.cycle({arm.get(), gripper.get()});
      const OperatingStateValue g = gripper->operating_state().state;
      gripper_faults += g == OperatingStateValue::fault && previous != OperatingStateValue::fault;
      previous = g;
      both_enabled +=
          arm->operating_state().state == OperatingStateValue::enabled && g == OperatingStateValue::enabled;
    }
  }
  const auto counts = window.counts();
  EXPECT_EQ(gripper_faults, 3) << "the silent node, its error EMCY, its reboot";
  EXPECT_EQ(gripper->status().warnings, 1u) << "its warning EMCY";
  EXPECT_TRUE(rebooted_enabling);
  EXPECT_TRUE(rig.io_node->configured) << "configured again after its reboot";
  EXPECT_EQ(gripper->operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(arm->operating_state().state, OperatingStateValue::fault) << "its drive's fault, not re-enabled";
  EXPECT_EQ(arm->fault_reason(), FaultReason::emcy);
  EXPECT_GT(both_enabled, 400);
  EXPECT_GE(sdo_ok, 10) << "runtime SDO uploads (one may meet the re-configuration or the silent node)";
  EXPECT_EQ(rig.task->counters().syncs, static_cast<std::uint64_t>(cycles));
  EXPECT_EQ(rig.task->counters().dropped, 0u);
  EXPECT_EQ(counts.cycles, 2u * cycles) << "each client's task cycle is one";
  EXPECT_RT_CLEAN(counts);
}

// The canopen_bus component's two tasks (route, then its `_sync` task: the clients' frames and
// SYNC) and an arm between them, stepped by the manager: every task's cycle under the guard.
TEST(RtGuard, CanopenBusComponentsTwoPhasesAndAClientAreRtClean) {
  saw::testing::GuardWindow window;
  RingNetwork network;
  RingPort& port = network.attach("shared");
  Drives drives{network, {}};
  drives.add(network, {1, 2});
  CanopenBusConfig b;
  b.uri = "test:guard-phases";
  b.heartbeat_period = 10 * ms;
  b.heartbeat_timeout = 50 * ms;
  saw::Manager m;
  auto& bus = static_cast<CanopenBus&>(m.add(
      std::make_unique<CanopenBus>("guard-bus", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), b,
                                   std::make_unique<Borrowed>(port))));
  CanopenArmConfig c = client("guard-bus", {1, 2});
  saw::TimeNs now = 0;
  c.startup_pause = [&] {
    drives.step(now);
    now += ms;
    port.now = now;
    return now;
  };
  auto& arm = static_cast<CanopenArm&>(m.add(
      std::make_unique<CanopenArm>("arm", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), c)));
  saw::TaskConfig late = saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0);
  late.offset = std::chrono::microseconds(900);
  saw::testing::BodyTask nodes("nodes", late, [&](std::uint64_t) {
    drives.step(nodes.now());
    port.now = nodes.now() + ms;
  });
  m.add(nodes);
  constexpr int periods = 2000;
  m.start_stepped(1'000'000'000);
  m.step_until(1'000'000'000 + (periods - 1) * ms);
  m.stop();
  const auto counts = window.counts();
  EXPECT_EQ(arm.operating_state().state, OperatingStateValue::enabled);
  EXPECT_EQ(bus.bus_task().counters().syncs, static_cast<std::uint64_t>(periods));
  EXPECT_EQ(counts.cycles, 4u * periods) << "the route task, the arm, the sync task, the nodes";
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
