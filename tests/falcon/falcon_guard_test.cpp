// The falcon component's cycle on the simulated firmware (packet codec, exchange, kinematics,
// homing, forces, the watchdog, corrupt frames, faults and their recovery) allocates, locks,
// waits and prints nothing: checked by the RT guard on every cycle.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "falcon_rig.hpp"
#include "guard_support.hpp"
#include "saw/drivers/falcon/threaded_transport.hpp"
#include "saw/rt_context.hpp"

namespace {

using namespace saw::drivers::falcon;

TEST(RtGuard, FalconCycleOnTheSimulatedFirmwareIsRtClean) {
  saw::testing::GuardWindow window;
  test::FalconRig rig;  // set-up and open: not RT
  constexpr int cycles = 3000;
  int enabled = 0;
  {
    saw::RtContextScope rt;
    for (int i = 0; i < cycles; ++i) {
      saw::RtCycleScope cycle("falcon");
      rig.sim->set_hand(rig.homed());  // the operator takes the grip once it has homed
      const bool commanding = rig.homed() && (i < 1500 || i > 1600);
      if (commanding) {
        const double s = std::sin(i * 0.01);
        rig.force(i == 2000 ? NAN : s, -s, 0.5 * s);
      }
      if (i == 1200) rig.sim->set_buttons(status::button_center);
      if (i == 1300) rig.sim->set_buttons(0);
      if (i == 1700) rig.sim->corrupt_answers(20);  // past max_missed: FAULT
      if (i == 1800) rig.write("state_command", saw::StateCommand::enable);
      if (i == 2200) rig.sim->drop_answers(3);
      rig.cycle();
      enabled += rig.state() == saw::OperatingStateValue::enabled;
    }
  }
  const auto counts = window.counts();
  EXPECT_TRUE(rig.homed());
  EXPECT_EQ(rig.state(), saw::OperatingStateValue::enabled);
  EXPECT_EQ(rig.device->device_status().faults, 1u);
  EXPECT_EQ(rig.device->device_status().refused.total(), 1u);
  EXPECT_EQ(rig.device->watchdog_trips(), 1u);
  EXPECT_EQ(rig.device->summary().no_answer, 3u);
  EXPECT_GT(enabled, 2500);
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

// The cycle's side of the I/O-thread transport (post a command, take a report) is RT-clean too;
// the I/O thread itself is not an RT path here (on USB it runs libusb, which allocates).
TEST(RtGuard, FalconCycleThroughTheIoThreadIsRtClean) {
  saw::testing::GuardWindow window;
  FalconConfig c;
  c.max_missed = 100;  // a shared machine: the I/O thread may be late now and then
  FalconDevice device("falcon", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0), c,
                      std::make_unique<ThreadedTransport>(std::make_unique<SimTransport>(), 0));
  device.state_table().finalize();
  device.startup();
  constexpr int cycles = 500;
  saw::TimeNs now = 1'000'000'000;
  for (int i = 0; i < cycles; ++i) {
    {
      saw::RtContextScope rt;
      saw::RtCycleScope cycle("falcon io");
      saw::detail::Access::step(device, now += 1'000'000);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(500));  // the period's rest, not RT
  }
  const auto counts = window.counts();
  device.cleanup();
  EXPECT_EQ(device.device_status().faults, 0u);
  EXPECT_GT(device.summary().exchanges - device.summary().no_answer, 300u);
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
