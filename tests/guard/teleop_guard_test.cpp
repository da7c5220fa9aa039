// The teleoperation task (law, ratchet, Ruckig offsets, prediction) and the delay task do not
// allocate or lock in their cycles.
#include <gtest/gtest.h>

#include "../teleop/fake_device.hpp"
#include "alloc_guard.hpp"
#include "saw/teleop/collaborative_control_force.hpp"
#include "saw/teleop/delay_task.hpp"

namespace {

using namespace std::chrono_literals;

TEST(AllocationGuard, TeleoperationCycleDoesNotAllocateOrLock) {
  saw::teleop::TeleopConfig c;
  c.limits = {2, 2};  // low: the ratchet and the Ruckig offset trajectory both run
  c.prediction = {true, 0.02};
  c.align = true;
  c.stale_timeout = 0.1;
  saw::testing::FakeDevice master("master"), slave("slave");
  saw::teleop::DelayTask delay("delay", saw::TaskConfig::periodic(1ms, 0), 0.02);
  saw::teleop::CollaborativeControlForce teleop("teleop", saw::TaskConfig::periodic(1ms, 0), c);
  saw::Manager m;
  m.add(master);
  m.add(slave);
  m.add(delay);
  m.add(teleop);
  m.connect("delay", "source", "master", "arm");
  m.connect("teleop", "master", "delay", "arm");
  m.connect("teleop", "slave", "slave", "arm");
  m.start_stepped();
  saw::testing::Stepper step{m};
  step({&master, &slave});  // first cycle outside the measurement: nothing special, but honest
  saw::testing::guard_reset();
  bool ratcheted = false;
  for (int i = 0; i < 1000; ++i) {
    master.position[0] = 0.1 * std::sin(i * 0.01);
    master.velocity[0] = 10 * std::cos(i * 0.01) * 0.01;
    if (i == 300) master.press_clutch(true);
    if (i == 400) master.press_clutch(false);
    step({&master, &slave});
    bool r = false;
    (void)teleop.state_table().read_latest(teleop.columns().ratcheting, r);
    ratcheted = ratcheted || r;
  }
  const auto counts = saw::testing::guard_counts();
  m.stop();
  EXPECT_TRUE(ratcheted) << "the scenario should have exercised the ratchet";
  EXPECT_EQ(counts.allocations, 0u) << "first size " << counts.first_allocation_size;
  EXPECT_EQ(counts.locks, 0u);
}

}  // namespace
