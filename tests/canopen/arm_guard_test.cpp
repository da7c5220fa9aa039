// A CanopenArm's cycle with three drives (bus master, CiA 402 controllers, KDL, checks, faults
// and their recovery, the watchdog, runtime SDO, a warning EMCY, a drive leaving operational, the
// master's heartbeat, a drive that rebooted configured again, one that rebooted during an enable)
// allocates, locks, waits and prints nothing:
// checked by the RT guard on every cycle, the in-process drives included.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <string>

#include "arm_rig.hpp"
#include "guard_support.hpp"
#include "saw/rt_context.hpp"

namespace {

using namespace saw::canopen;
using namespace saw::canopen::test;
using saw::OperatingStateValue;
using saw::StateCommand;
using saw::Wrench;

TEST(RtGuard, CanopenArmCycleWithThreeDrivesIsRtClean) {
  saw::testing::GuardWindow window;
  TestDriveConfig soft;  // well damped: the forces below move the joints a few tenths of a radian
  soft.torque_gain = 20;
  soft.damping = 20;
  ArmRig rig(arm_config(cia402::cst), soft);  // set-up and start-up: not RT
  SdoQueue& sdo = rig.arm->master().sdo_queue();

  constexpr int cycles = 4000;
  int enabled_cycles = 0, replies = 0, ok_replies = 0;
  // Each fault as it came: its cycle and reason (the array is written in the cycle, read after).
  std::array<std::pair<int, FaultReason>, 8> faults{};
  std::uint32_t seen = 0;
  bool rebooted_enabling = false;
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("canopen arm");
      // What a client and the world do this cycle.
      if (i == 0 || i == 950 || i == 1450 || i == 1850) rig.state_command(StateCommand::enable);
      const bool commanding = i >= 20 && (i < 2200 || i > 2300);
      if (commanding) {
        const double s = 0.2 * std::sin(i * 0.01);
        rig.write("servo_cf", i == 2500 ? Wrench{{NAN, 0, 0}, {0, 0, 0}} : Wrench{{s, s, -s}, {0, 0, 0}});
      }
      if (i == 800) rig.drives[2].raise_fault(0x2310);
      if (i == 900) rig.drives[2].clear_fault();
      if (i == 1300) rig.drives[1].set_heartbeat_silent(true);
      if (i == 1400) rig.drives[1].set_heartbeat_silent(false);
      if (i == 1800) rig.network.state = saw::can::BusState::bus_off;
      if (i == 1805) rig.network.state = saw::can::BusState::error_active;
      if (i == 3000) rig.drives[0].warn(0x4210, 0x09);  // a warning: no fault
      if (i == 3100) rig.drives[1].set_nmt(NmtCommand::enter_pre_operational);
      if (i == 3200) rig.drives[1].set_nmt(NmtCommand::start);
      if (i == 3300) rig.state_command(StateCommand::enable);
      if (i == 3500) rig.drives[2].reboot();  // configured again by the next enable, from the cycle
      if (i == 3600) rig.state_command(StateCommand::enable);
      if (i == 3605) {  // during that enable: configured again by it, logged
        rebooted_enabling = rig.arm->enabling();
        rig.drives[0].reboot();
      }
      if (i % 100 == 50) {
        SdoRequest q;
        q.node = static_cast<std::uint8_t>(1 + (i / 100) % 3);
        q.index = 0x1000;
        (void)sdo.submit(q);
      }
      for (SdoReply r; sdo.take_reply(r);) {
        ++replies;
        ok_replies += r.ok();
      }
      rig.cycle();
      enabled_cycles += rig.state() == OperatingStateValue::enabled;
      if (rig.arm->status().faults != seen && seen < faults.size())
        faults[seen++] = {i, rig.arm->fault_reason()};
    }
  }
  const auto counts = window.counts();
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled) << "recovered from every fault";
  std::string history;
  for (std::uint32_t k = 0; k < seen; ++k)
    history += std::to_string(faults[k].first) + ": " + to_string(faults[k].second) + "; ";
  EXPECT_EQ(rig.arm->status().faults, 5u)
      << "the drive fault, the lost heartbeat, bus-off, the drive leaving operational, the reboot: "
      << history;
  EXPECT_EQ(faults[3].second, FaultReason::nmt_left) << history;
  EXPECT_EQ(faults[4].second, FaultReason::node_rebooted) << history;
  EXPECT_EQ(rig.drives[2].nmt_state(), saw::canopen::NmtState::operational);
  EXPECT_TRUE(rebooted_enabling);
  EXPECT_EQ(rig.drives[0].nmt_state(), saw::canopen::NmtState::operational);
  EXPECT_EQ(rig.arm->status().warnings, 1u);
  EXPECT_EQ(rig.arm->status().last_warning, 0x4210u);
  EXPECT_GT(rig.arm->master().counters().heartbeats, 30u) << "the master's own, every 100 ms";
  EXPECT_GT(enabled_cycles, 2500);
  EXPECT_EQ(rig.arm->watchdog_trips(), 1u);
  EXPECT_EQ(rig.arm->device_status().refused.not_finite, 1u);
  EXPECT_EQ(replies, cycles / 100);
  EXPECT_GE(ok_replies, cycles / 100 - 3) << "(a transfer may fail while the bus is off)";
  EXPECT_EQ(rig.arm->status().syncs, static_cast<std::uint64_t>(cycles));
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
