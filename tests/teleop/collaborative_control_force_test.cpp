// The teleoperation task against fake devices, on the stepped clock: clutch, ratchet, faults,
// jerk-limited offsets, run-time settings, delay and prediction.
#include <gtest/gtest.h>

#include <cmath>

#include "saw/teleop/teleoperation.hpp"
#include "saw/testing/teleop_rig.hpp"
#include "teleop_support.hpp"

namespace {

using saw::testing::basic;
using saw::testing::dist;
using saw::testing::norm;
using saw::testing::Rig;
using saw::testing::TeleopConfig;

TEST(CollaborativeControlForce, EnablingWithDevicesApartMakesNoForce) {
  Rig rig(basic());
  rig.master.position = {0.05, 0.01, 0};
  rig.slave.position = {-0.02, 0.03, 0.01};
  rig.step(3);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_LT(norm(rig.master.force), 1e-9);
  EXPECT_LT(norm(rig.slave.force), 1e-9);
  // Then the master moves: the slave is pulled the same way, the master back.
  rig.master.position = {0.06, 0.01, 0};
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0], 1.0, 1e-9);
  EXPECT_NEAR(rig.master.force[0], -1.0, 1e-9);
}

TEST(CollaborativeControlForce, ClutchTurnsForcesOffAndReleasesWithoutJump) {
  Rig rig(basic());
  rig.step(2);
  rig.master.press_clutch(true);
  rig.step(1);
  for (int i = 0; i < 50; ++i) {  // the operator repositions the master by 5 cm
    rig.master.position[1] += 0.001;
    rig.step(1);
    EXPECT_LT(norm(rig.slave.force), 1e-12);
    EXPECT_LT(norm(rig.master.force), 1e-12);
  }
  rig.master.press_clutch(false);
  rig.step(2);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "releasing the clutch must not jump";
  rig.master.position[1] += 0.01;  // teleoperation resumes from the new offset
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[1], 1.0, 1e-9);
}

// A homing device (a Falcon: its counts are relative until homed, then jump) holds the
// teleoperation: no force either side while busy, none on the cycle its position jumps, and the
// held cycles are not counted in the tracking figures.
TEST(CollaborativeControlForce, ABusyDeviceHoldsTheTeleoperationAndItsJumpIsNotFollowed) {
  Rig rig(basic());
  rig.step(2);
  const auto counted = rig.teleop.enabled_cycles();
  rig.master.busy = true;
  for (int i = 0; i < 20; ++i) {  // homing drives the master's (relative) position 4 cm
    rig.master.position[2] += 0.002;
    rig.step(1);
    EXPECT_LT(norm(rig.slave.force), 1e-12);
    EXPECT_LT(norm(rig.master.force), 1e-12);
  }
  EXPECT_EQ(rig.teleop.enabled_cycles(), counted) << "held cycles are not tracking";
  rig.master.busy = false;
  rig.master.position = {0.03, -0.02, 0.01};  // homed: absolute now, in the same row
  rig.step(1);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "the jump on leaving busy must not be followed";
  EXPECT_LT(norm(rig.master.force), 1e-9);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  rig.master.position[0] += 0.01;  // and teleoperation resumes from there
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0], 1.0, 1e-9);
  EXPECT_GT(rig.teleop.enabled_cycles(), counted);
}

TEST(CollaborativeControlForce, RatchetSlipsAtTheLimitAndResumesBelowIt) {
  TeleopConfig c = basic();
  c.offset_limits = {0.5, 20, 1000};
  Rig rig(c);
  rig.step(2);
  // The slave is blocked; the operator pushes the master 10 cm: the force would be 10 N.
  double max_force = 0;
  bool ratcheted = false;
  for (int i = 0; i < 100; ++i) {
    rig.master.position[0] += 0.001;
    rig.step(1);
    max_force = std::max(max_force, norm(rig.master.force));
    bool r = false;
    ASSERT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().ratcheting, r), saw::Status::ok);
    ratcheted = ratcheted || r;
  }
  EXPECT_TRUE(ratcheted);
  EXPECT_LE(max_force, 3.0 + 1e-9);
  rig.step(200);  // the push stops: the force holds at the limit while the operator holds
  EXPECT_NEAR(norm(rig.master.force), 3.0, 1e-6);
  rig.master.position[0] -= 0.005;  // the operator backs off 5 mm: below the limit again
  rig.step(2);
  EXPECT_NEAR(norm(rig.master.force), 2.5, 1e-6);
  bool still = true;
  ASSERT_EQ(rig.teleop.state_table().read_latest(rig.teleop.columns().ratcheting, still), saw::Status::ok);
  EXPECT_FALSE(still);
  // Teleoperation resumed: moving the master back 1 cm changes the slave force by k·1 cm.
  const double before = rig.slave.force[0];
  rig.master.position[0] -= 0.01;
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0] - before, -1.0, 1e-6);
}

TEST(CollaborativeControlForce, ScaleChangeDoesNotJumpAndTakesEffect) {
  TeleopConfig c = basic();
  c.limits = {100, 100};
  Rig rig(c);
  rig.master.position = {0.1, 0, 0};
  rig.step(3);
  rig.master.position = {0.11, 0, 0};  // an error of 1 cm: 1 N on the slave
  rig.step(2);
  ASSERT_NEAR(rig.slave.force[0], 1.0, 1e-9);
  ASSERT_EQ(rig.op.set_scale(0.5), saw::Status::ok);
  saw::Vec3 last = rig.slave.force;
  double max_step = 0;
  for (int i = 0; i < 10; ++i) {
    rig.step(1);
    max_step = std::max(max_step, dist(rig.slave.force, last));
    last = rig.slave.force;
  }
  // Applied naively, the new S⁻¹ would step the slave force by k·0.5·0.11 m = 5.5 N.
  EXPECT_LT(max_step, 1e-9);
  rig.master.position[0] += 0.02;  // now 2 cm of master motion asks 1 cm of the slave
  rig.step(2);
  EXPECT_NEAR(rig.slave.force[0], 2.0, 1e-9);
}

TEST(CollaborativeControlForce, AlignmentPullsTheSlaveAlongAJerkLimitedPath) {
  TeleopConfig c = basic();
  c.limits = {100, 100};
  c.align = true;
  c.slave_offset = {0, 0, 0};  // absolute mode: the slave goes where the master is
  c.offset_limits = {0.05, 0.5, 10};
  Rig rig(c);
  rig.master.position = {0.05, 0, 0};
  double max_step = 0;
  saw::Vec3 last{};
  for (int i = 0; i < 3000; ++i) {
    rig.step(1);
    max_step = std::max(max_step, dist(rig.slave.force, last));
    last = rig.slave.force;
  }
  // A jump would be k·5 cm = 5 N in one cycle; the offset moves at ≤ 5 cm/s: ≤ 0.005 N/cycle.
  EXPECT_LE(max_step, 0.005 + 1e-9);
  EXPECT_NEAR(rig.slave.force[0], 5.0, 1e-6) << "the offset reached its configured value";
}

// The offset's limits are a run-time setting: faster limits set while it travels bring it there
// sooner; limits outside their range are refused, counted, and leave those in force.
TEST(CollaborativeControlForce, OffsetLimitsSetAtRunTimeChangeTheAlignment) {
  TeleopConfig c = basic();
  c.limits = {100, 100};
  c.align = true;
  c.slave_offset = {0, 0, 0};
  c.offset_limits = {0.01, 0.1, 1};  // 5 cm at 1 cm/s: more than 5 s
  Rig rig(c);
  rig.master.position = {0.05, 0, 0};
  rig.step(100);
  ASSERT_LT(rig.slave.force[0], 1.0) << "still travelling at the slow limits";
  ASSERT_EQ(rig.op.set_offset_limits({50, 20, 1000}), saw::Status::ok);  // 50 m/s: out of range
  rig.step(2);
  EXPECT_EQ(rig.teleop.rejected_commands(), 1u);
  saw::teleop::OffsetLimits in_force;
  const auto* read = rig.teleop.provided("teleop")->find_command("offset_limits");
  ASSERT_NE(read, nullptr);
  ASSERT_EQ(read->read(nullptr, &in_force), saw::Status::ok);
  EXPECT_EQ(in_force.velocity, 0.01);
  ASSERT_EQ(rig.op.set_offset_limits({0.5, 20, 1000}), saw::Status::ok);
  rig.step(900);  // 1 s in all: the slow limits would have carried it 1 cm at most
  ASSERT_EQ(read->read(nullptr, &in_force), saw::Status::ok);
  EXPECT_EQ(in_force.velocity, 0.5);
  EXPECT_NEAR(rig.slave.force[0], 5.0, 1e-6) << "the offset reached its configured value";
  EXPECT_EQ(rig.teleop.offset_errors(), 0u);
}

TEST(CollaborativeControlForce, StaleMasterFaultsWithZeroForceUntilReEnabled) {
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  Rig rig(c);
  rig.step(3);
  rig.master.position[0] += 0.01;
  rig.step(1);
  ASSERT_GT(norm(rig.slave.force), 0.5);
  rig.step(5, false);  // the master stops publishing: 5 ms is not yet stale
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  rig.step(2, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, saw::teleop::FaultCode::input_stale);
  EXPECT_EQ(rig.teleop.fault().source_name(), "master");
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  EXPECT_EQ(norm(rig.master.force), 0.0);
  rig.step(5);  // fresh again: still faulted until someone enables
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::enable), saw::Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_LT(norm(rig.slave.force), 1e-9);
}

TEST(CollaborativeControlForce, RejectsBadSettings) {
  Rig rig(basic());
  ASSERT_EQ(rig.op.set_scale(std::nan("")), saw::Status::ok);  // queued, then rejected by the task
  ASSERT_EQ(rig.op.set_scale(-1), saw::Status::ok);
  ASSERT_EQ(rig.op.set_gains({std::numeric_limits<double>::infinity(), 1}), saw::Status::ok);
  ASSERT_EQ(rig.op.set_prediction({true, -0.1}), saw::Status::ok);
  rig.step(2);
  EXPECT_EQ(rig.teleop.rejected_commands(), 4u);
  rig.master.position[0] = 0.01;
  rig.step(1);
  EXPECT_NEAR(rig.slave.force[0], 1.0, 1e-9) << "the old gains and scale still hold";
}

TEST(CollaborativeControlForce, DisableAndPauseZeroTheForces) {
  Rig rig(basic());
  rig.step(2);
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::pause), saw::Status::ok);
  rig.master.position[0] = 0.02;
  rig.step(2);
  saw::OperatingState s;
  ASSERT_EQ(rig.op.operating_state(s), saw::Status::ok);
  EXPECT_EQ(s.state, saw::OperatingStateValue::paused);
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  ASSERT_EQ(rig.op.state_command(saw::StateCommand::resume), saw::Status::ok);
  rig.step(2);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "resuming re-aligns the offsets";
}

// Constant-velocity master behind a 20 ms delay: the slave force reflects a 20 ms-old master
// position unless the local model predicts it forward.
double delayed_error(bool predict) {
  TeleopConfig c = basic();
  c.limits = {100, 100};
  c.stale_timeout = 0.1;
  c.prediction = {predict, 0.020};
  saw::testing::DelayedTeleopRig rig(c, 0.020);
  rig.step(50);           // at rest while teleoperation engages
  const double v = 0.05;  // then 5 cm/s along x
  rig.master.velocity = {v, 0, 0};
  for (int i = 0; i < 300; ++i) {
    rig.master.position[0] += v * 0.001;
    rig.step();
  }
  // Slave force = −k·e_s = k·(d_m − d_s): how far the slave's goal has moved, in metres.
  const double goal_moved = rig.slave.force[0] / 100.0;
  return rig.master.position[0] - goal_moved;  // the goal's lag behind the real master
}

TEST(CollaborativeControlForce, EulerPredictionCompensatesTheDelay) {
  const double lag_without = delayed_error(false);
  const double lag_with = delayed_error(true);
  EXPECT_NEAR(lag_without, 0.05 * 0.020, 1e-4) << "the delay shows as v·delay = 1 mm of lag";
  EXPECT_LT(std::abs(lag_with), 0.1e-3) << "the local model predicts the master forward over the delay";
}

}  // namespace

namespace {

TEST(CollaborativeControlForce, WaitsForInputsAtStartUpThenFaultsIfTheyNeverCome) {
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  Rig rig(c);
  rig.step(4, false);  // the master has published nothing yet: not a fault, not yet
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_EQ(norm(rig.slave.force), 0.0);
  rig.step(3, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, saw::teleop::FaultCode::input_missing);
  EXPECT_EQ(rig.teleop.fault().source_name(), "master");
}

TEST(CollaborativeControlForce, AStartupTimeoutWaitsLongerForARemoteMasterThenFollowsIt) {
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  c.startup_timeout = 0.050;  // a master across DDS may take a while to start streaming
  Rig rig(c);
  rig.step(40, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled)
      << "still within startup_timeout";
  rig.step(5);  // the master starts publishing: teleoperation runs, no fault
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  rig.step(10, false);  // and once seen, its silence is a fault after stale_timeout, not startup_timeout
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, saw::teleop::FaultCode::input_stale);
  EXPECT_EQ(rig.teleop.fault().source_name(), "master");
}

TEST(CollaborativeControlForce, AStartupTimeoutEndsInAFaultIfTheMasterNeverComes) {
  TeleopConfig c = basic();
  c.stale_timeout = 0.005;
  c.startup_timeout = 0.020;
  Rig rig(c);
  rig.step(15, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  rig.step(10, false);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
}

}  // namespace

// A controller that cannot drive its devices says so: enabled but busy while a device is
// disabled, no force either side, nothing counted as tracking; a device that stays disabled for
// device_timeout faults the task naming the side; one enabled in time is followed from where it is.
namespace {

TEST(CollaborativeControlForce, ADisabledDeviceIsWaitedForBusyThenFaultsNamingItsSide) {
  TeleopConfig c = basic();
  c.device_timeout = 0.05;
  Rig rig(c);
  rig.step(2);
  ASSERT_FALSE(rig.teleop.state().is_busy);
  rig.slave.operating = saw::OperatingStateValue::disabled;
  const auto counted = rig.teleop.enabled_cycles();
  rig.master.position[0] += 0.01;
  rig.step(20);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::enabled);
  EXPECT_TRUE(rig.teleop.state().is_busy) << "waiting for the slave: not plainly enabled";
  EXPECT_LT(norm(rig.slave.force), 1e-12);
  EXPECT_LT(norm(rig.master.force), 1e-12);
  EXPECT_EQ(rig.teleop.enabled_cycles(), counted);
  rig.slave.operating = saw::OperatingStateValue::enabled;  // enabled in time: followed from here
  rig.step(2);
  EXPECT_FALSE(rig.teleop.state().is_busy);
  EXPECT_LT(norm(rig.slave.force), 1e-9) << "no jump when the slave comes back";
  rig.slave.operating = saw::OperatingStateValue::disabled;
  rig.step(60);
  EXPECT_EQ(rig.teleop.operating_state(), saw::OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.fault().code, saw::FaultCode::device_disabled);
  EXPECT_NE(saw::to_string(rig.teleop.fault()).find("slave device not enabled"), std::string::npos)
      << saw::to_string(rig.teleop.fault());
  EXPECT_FALSE(rig.teleop.state().is_busy);
}

}  // namespace
