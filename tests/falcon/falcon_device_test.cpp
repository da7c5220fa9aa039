// The `falcon` component on the simulated firmware: homing, forces, clutch, limits, watchdog, faults.
#include <gtest/gtest.h>

#include <cmath>

#include "falcon_rig.hpp"

namespace saw::drivers::falcon {
namespace {

using test::FalconRig;

Eigen::Vector3d position(FalconRig& r) {
  const Pose p = r.read<Pose>("measured_cp");
  return {p.position[0], p.position[1], p.position[2]};
}

TEST(FalconDevice, HomesAtStartWithBlueThenGreenLeds) {
  FalconRig rig;
  rig.cycle();
  EXPECT_TRUE(rig.device->homing());
  EXPECT_EQ(rig.sim->leds(), control::led_blue);
  EXPECT_TRUE(rig.sim->homing_mode());
  // Busy (a teleoperation holds) while the counts are relative, from the first cycle.
  EXPECT_TRUE(rig.device->operating_state().is_busy);
  const int cycles = rig.cycle_until([&] { return rig.homed(); });
  std::printf("homed in %d cycles\n", cycles);
  EXPECT_LT(cycles, 2000);
  rig.cycle(2);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_EQ(rig.sim->leds(), control::led_green);
  EXPECT_FALSE(rig.sim->homing_mode());
  EXPECT_FALSE(rig.device->operating_state().is_busy);
  // Homed: the measured pose is the firmware's true tip, relative to the encoder-zero pose.
  DeltaKinematics k;
  Eigen::Vector3d zero;
  ASSERT_TRUE(k.forward(k.angles({0, 0, 0}), zero));
  EXPECT_LT((position(rig) - (rig.sim->tip() - zero)).norm(), 5e-4);
}

TEST(FalconDevice, ServoCfPushesTheTipAlongTheForce) {
  FalconRig rig;
  rig.home();
  rig.sim->set_hand(true);  // the operator's hand holds the grip mid-workspace (200 N/m)
  rig.cycle(500);
  const Eigen::Vector3d start = position(rig);
  for (int i = 0; i < 300; ++i) rig.force(1.0, 0, 0), rig.cycle();
  const Eigen::Vector3d moved = position(rig) - start;
  EXPECT_GT(moved.x(), 1e-3) << moved.transpose();
  EXPECT_GT(moved.x(), 3 * std::hypot(moved.y(), moved.z())) << moved.transpose();
  const Vec3 applied = rig.read<Vec3>("servo_force");
  EXPECT_EQ(applied[0], 1.0);
  EXPECT_NEAR(moved.x(), 1.0 / 200, 1e-3) << "the hand's spring balances the force";
}

TEST(FalconDevice, NonFiniteOrTooLargeForcesAreRefusedAndCounted) {
  FalconRig rig;
  rig.home();
  rig.force(NAN, 0, 0);
  rig.cycle();
  rig.force(0, 0, 50);
  rig.cycle();
  EXPECT_EQ(rig.device->device_status().refused.total(), 2u);
  EXPECT_TRUE(rig.sim->motor_torque().isZero());
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
}

TEST(FalconDevice, TheWatchdogDropsTheForceWhenCommandsStop) {
  FalconRig rig;
  rig.home();
  rig.force(0, 0, 1);
  rig.cycle();
  EXPECT_FALSE(rig.sim->motor_torque().isZero());
  rig.cycle(5);
  EXPECT_TRUE(rig.sim->motor_torque().isZero());
  EXPECT_TRUE(rig.read<bool>("command_timeout"));
  EXPECT_EQ(rig.read<std::uint64_t>("watchdog_trips"), 1u);
}

TEST(FalconDevice, OutsideTheWorkspaceNoForcePushesFurtherOut) {
  FalconConfig c;
  c.workspace_min = Eigen::Vector3d::Constant(-0.001);
  c.workspace_max = Eigen::Vector3d(0.001, 0.06, 0.06);
  FalconRig rig(c);
  rig.home();
  rig.sim->set_hand(true);
  rig.cycle(500);
  for (int i = 0; i < 400; ++i) rig.force(2.0, 0, 0), rig.cycle();
  EXPECT_LT(position(rig).x(), 0.002)
      << "held near the wall at x = 1 mm, not at the 10 mm the force would reach";
  EXPECT_EQ(rig.read<Vec3>("servo_force")[0], 0.0);
}

// The grip buttons' events: arm_interface_test.cpp (they need a connected client).

TEST(FalconDevice, CorruptFramesAreRefusedAndPastTheLimitFaultWithZeroForce) {
  FalconRig rig;
  rig.home();
  rig.sim->corrupt_answers(5);
  for (int i = 0; i < 5; ++i) rig.force(0, 0, 1), rig.cycle();
  EXPECT_EQ(rig.device->summary().bad_frames, 5u);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled) << "5 ≤ max_missed";
  rig.sim->corrupt_answers(11);
  for (int i = 0; i < 11; ++i) rig.force(0, 0, 1), rig.cycle();
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::device_error);
  rig.cycle();
  EXPECT_TRUE(rig.sim->motor_torque().isZero());
  EXPECT_EQ(rig.sim->leds(), control::led_red);
  EXPECT_EQ(rig.read<FaultInfo>("fault").code, FaultCode::device_error);
  // Enable again: it answers, so it stays enabled.
  rig.write("state_command", StateCommand::enable);
  rig.cycle(3);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
}

TEST(FalconDevice, MissedExchangesPastTheLimitFaultAsDeviceLost) {
  FalconConfig c;
  c.max_missed = 3;
  FalconRig rig(c);
  rig.home();
  rig.sim->drop_answers(3);
  rig.cycle(3);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  rig.sim->drop_answers(4);
  rig.cycle(4);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::device_lost);
  EXPECT_EQ(rig.device->summary().no_answer, 7u);
}

TEST(FalconDevice, AnUnplugFaultsAtOnce) {
  FalconRig rig;
  rig.home();
  rig.sim->unplug();
  rig.cycle();
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::device_lost);
  EXPECT_NE(to_string(rig.device->fault()).find("usb device lost"), std::string::npos);
}

TEST(FalconDevice, HomingThatNeverFinishesFaults) {
  FalconConfig c;
  c.homing_dac = 0;  // the arms never reach their index
  c.homing_timeout = 50'000'000;
  FalconRig rig(c);
  rig.cycle(60);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::limit_exceeded);
  EXPECT_EQ(rig.device->fault().source_name(), "homing");
}

}  // namespace
}  // namespace saw::drivers::falcon
