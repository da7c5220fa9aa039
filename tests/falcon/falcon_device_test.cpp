// The `falcon` component on the simulated firmware: homing, forces, clutch, limits, watchdog, faults.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "falcon_rig.hpp"

namespace saw::drivers::falcon {
namespace {

using test::FalconRig;

Eigen::Vector3d position(FalconRig& r) {
  const Pose p = r.read<Pose>("measured_cp");
  return {p.position[0], p.position[1], p.position[2]};
}

// The LEDs as the simulated firmware reads them with libnifalcon's enum (not the driver's
// constants). Catches the LED bits of libnifalcon's stale header comment, which showed homing
// red and "homed" blue. Homing is the operator's gesture (the simulated hand pulls the grip out
// and pushes it in): the motors get no force meanwhile, as with libnifalcon. Catches the +500
// DAC push that was the only way ours homed. The homing bit stays set once homed: catches it
// cleared after homing (the firmware then stops reporting homed, and homing loss goes unseen).
TEST(FalconDevice, HomesAtStartByTheOperatorsGestureWithBlueThenGreenLeds) {
  FalconRig rig;
  rig.cycle();
  EXPECT_TRUE(rig.device->homing());
  EXPECT_EQ(rig.sim->led(), SimLed::blue);
  EXPECT_TRUE(rig.sim->homing_mode());
  // Busy (a teleoperation holds) while the counts are relative, from the first cycle.
  EXPECT_TRUE(rig.device->operating_state().is_busy);
  double largest_torque = 0;
  const int cycles = rig.cycle_until([&] {
    largest_torque = std::max(largest_torque, rig.sim->motor_torque().norm());
    return rig.homed();
  });
  std::printf("homed in %d cycles\n", cycles);
  EXPECT_LT(cycles, 2000);
  EXPECT_EQ(largest_torque, 0.0) << "no motor force while the operator homes";
  rig.cycle(200);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_EQ(rig.sim->led(), SimLed::green);
  EXPECT_TRUE(rig.sim->homing_mode()) << "the homing bit is held once homed";
  EXPECT_TRUE(rig.sim->homed(0) && rig.sim->homed(1) && rig.sim->homed(2));
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
  c.contract.workspace_min = {-0.001, -0.001, -0.001};
  c.contract.workspace_max = {0.001, 0.06, 0.06};
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
  EXPECT_EQ(rig.sim->led(), SimLed::red);
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

// The optional motor push (homing_dac) homes without the operator.
TEST(FalconDevice, AMotorPushHomesWhenConfigured) {
  FalconConfig c;
  c.homing_dac = 500;
  SimFirmwareConfig f;
  f.operator_homes = false;
  FalconRig rig(c, f);
  rig.cycle();
  EXPECT_GT(rig.sim->motor_torque().norm(), 0.0);
  EXPECT_LT(rig.cycle_until([&] { return rig.homed(); }), 2000);
  rig.cycle();
  EXPECT_TRUE(rig.sim->motor_torque().isZero());
}

// A homed Falcon whose status stops saying every arm is homed: FAULT saying so, zero force; an
// enable homes it again. Catches the driver that never looked at the homed bits once homed.
TEST(FalconDevice, HomingLostFaultsAndAnEnableHomesAgain) {
  FalconRig rig;
  rig.home();
  rig.cycle(10);
  rig.sim->lose_homing();
  rig.force(0, 0, 1);
  rig.cycle();
  ASSERT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_FALSE(rig.homed()) << "is_homed says what the device knows: not homed any more";
  EXPECT_EQ(rig.device->fault().source_name(), "homing");
  const auto reason = rig.device->device_status().reason;
  EXPECT_NE(std::string(reason.data()).find("homing lost"), std::string::npos) << reason.data();
  rig.force(0, 0, 1);
  rig.cycle();
  EXPECT_TRUE(rig.sim->motor_torque().isZero());
  EXPECT_EQ(rig.sim->led(), SimLed::red);
  rig.write("state_command", StateCommand::enable);
  rig.cycle();
  EXPECT_TRUE(rig.device->homing());
  EXPECT_LT(rig.cycle_until([&] { return !rig.device->homing(); }), 2000);
  rig.cycle(2);
  EXPECT_EQ(rig.state(), OperatingStateValue::enabled);
  EXPECT_TRUE(rig.homed());
  EXPECT_TRUE(rig.sim->homed(0) && rig.sim->homed(1) && rig.sim->homed(2));
  EXPECT_EQ(rig.device->device_status().faults, 1u);
}

TEST(FalconDevice, HomingThatNeverFinishesFaults) {
  FalconConfig c;
  c.contract.home_timeout = 50'000'000;
  SimFirmwareConfig f;
  f.operator_homes = false;  // nobody homes it, and no push (homing_dac 0)
  FalconRig rig(c, f);
  rig.cycle(60);
  EXPECT_EQ(rig.state(), OperatingStateValue::fault);
  EXPECT_EQ(rig.device->fault().code, FaultCode::limit_exceeded);
  EXPECT_EQ(rig.device->fault().source_name(), "homing");
}

}  // namespace
}  // namespace saw::drivers::falcon

namespace saw::drivers::falcon {
namespace {

// The arms turning at a steady 4 counts per period, homed from the start; after cycle 20 only
// every 4th exchange is answered. Its reports are built byte by byte here (not packet.cpp).
class SteadyArms final : public FalconTransport {
 public:
  void open() override {}
  ExchangeResult exchange(const Packet&, Packet& in) noexcept override {
    ++cycle_;
    if (cycle_ > 20 && cycle_ % 4 != 0) return {ExchangeStatus::no_answer, 0, 0};
    const auto e = static_cast<std::uint16_t>(4 * cycle_);
    in[0] = '<';
    for (std::size_t w = 0; w < 3; ++w)
      for (std::size_t k = 0; k < 4; ++k)
        in[1 + 4 * w + k] = static_cast<std::uint8_t>('A' + ((e >> (4 * k)) & 0xf));
    in[13] = 'A' + 0x70;  // every arm homed
    in[14] = 'A';
    in[15] = '>';
    return {ExchangeStatus::ok, packet_size, 0};
  }
  void close() noexcept override {}
  std::string describe() const override { return "steady arms"; }

 private:
  int cycle_ = 0;
};

// The velocity over the real interval between reports: 4 counts per ms all along, also across
// the 3 unanswered exchanges before each report. Catches the difference divided by one period
// (4 times too fast after every gap).
TEST(FalconDevice, VelocityIsOverTheIntervalBetweenReports) {
  FalconConfig c;
  c.velocity_filter = 1;  // the raw finite difference
  FalconDevice device("falcon", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c,
                      std::make_unique<SteadyArms>());
  device.state_table().finalize();
  device.startup();
  TimeNs now = 1'000'000'000;
  const double expected = 4 * DeltaKinematics{}.angle(1) - 4 * DeltaKinematics{}.angle(0);  // rad/ms
  for (int i = 0; i < 60; ++i, now += 1'000'000) {
    detail::Access::step(device, now);
    if (i < 25) continue;
    JointState js{};
    (void)device.provided("arm")->find_command("measured_js")->read(nullptr, &js);
    for (std::size_t k = 0; k < 3; ++k) EXPECT_NEAR(js.velocity[k], expected * 1e3, 1e-6) << "cycle " << i;
  }
  EXPECT_EQ(device.operating_state().state, OperatingStateValue::enabled);
}

}  // namespace
}  // namespace saw::drivers::falcon
