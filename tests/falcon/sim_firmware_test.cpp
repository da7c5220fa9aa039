// The simulated firmware through the seam: real packets, delta dynamics, homing, scripted faults.
#include "saw/drivers/falcon/sim_firmware.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace saw::drivers::falcon {
namespace {

DeviceReport exchange(SimTransport& t, const MotorCommand& c) {
  Packet in{};
  const ExchangeResult r = t.exchange(encode_command(c), in);
  EXPECT_EQ(r.status, ExchangeStatus::ok);
  DeviceReport d{};
  EXPECT_EQ(decode_report(in, d), FrameError::none);
  return d;
}

TEST(FalconSimFirmware, AnswersEveryCommandWithAValidReport) {
  SimTransport t;
  Packet in{};
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::disconnected);  // not open
  t.open();
  const DeviceReport r = exchange(t, {});
  EXPECT_EQ(r.buttons(), 0);
  t.firmware().set_buttons(status::button_center);
  EXPECT_EQ(exchange(t, {}).buttons(), status::button_center);
}

TEST(FalconSimFirmware, ADacCommandMovesTheArmsTheWayTheKinematicsSay) {
  SimTransport t;
  t.open();
  DeltaKinematics k;
  const Eigen::Vector3d x0 = t.firmware().tip();
  Eigen::Matrix3d j;
  ASSERT_TRUE(k.jacobian(t.firmware().angles(), x0, j));
  std::array<std::int16_t, 3> dac{};
  k.dac(j, Eigen::Vector3d(0, 0, 2.0), dac);  // 2 N along +z
  for (int i = 0; i < 50; ++i) exchange(t, {dac, 0});
  EXPECT_GT(t.firmware().tip().z() - x0.z(), 1e-3);
  EXPECT_LT(std::abs(t.firmware().tip().x() - x0.x()), 1e-3);
}

TEST(FalconSimFirmware, HomingModeReportsEachArmHomedAtItsIndex) {
  SimFirmwareConfig f;
  f.operator_homes = false;
  SimTransport t(f);
  t.open();
  const DeviceReport before = exchange(t, {});
  DeltaKinematics k;
  // Before homing the counts are off by the power-up offset.
  EXPECT_NE(before.encoder[0], k.encoder(t.firmware().angles()[0]));
  DeviceReport r{};
  for (int i = 0; i < 2000 && !(r.homed(0) && r.homed(1) && r.homed(2)); ++i)
    r = exchange(t, {{500, 500, 500}, control::homing | control::led_blue});  // arms up
  EXPECT_TRUE(r.homed(0) && r.homed(1) && r.homed(2));
  EXPECT_EQ(t.firmware().led(), SimLed::blue);
  r = exchange(t, {{}, control::homing});
  EXPECT_TRUE(r.homed(0) && r.homed(1) && r.homed(2)) << "homed while the bit is held";
  r = exchange(t, {});
  EXPECT_EQ(r.encoder[1], k.encoder(t.firmware().angles()[1]));
  EXPECT_FALSE(r.homed(0));  // homing status only in homing mode
  r = exchange(t, {{}, control::homing});
  EXPECT_FALSE(r.homed(0)) << "dropping the homing bit lost the homing";
}

// The operator's gesture: in homing mode with no force, the simulated hand pulls the grip out
// and pushes it in until the firmware reports every arm homed.
TEST(FalconSimFirmware, TheOperatorsGestureHomesWithoutMotorForce) {
  SimTransport t;
  t.open();
  DeviceReport r{};
  double deepest = 10, furthest = 0;
  int n = 0;
  for (; n < 2000 && !(r.homed(0) && r.homed(1) && r.homed(2)); ++n) {
    r = exchange(t, {{}, control::homing});
    deepest = std::min(deepest, t.firmware().tip().z());
    furthest = std::max(furthest, t.firmware().tip().z());
  }
  std::printf("homed by the gesture in %d exchanges, grip z %.1f..%.1f mm\n", n, deepest * 1e3,
              furthest * 1e3);
  EXPECT_TRUE(r.homed(0) && r.homed(1) && r.homed(2));
  EXPECT_TRUE(t.firmware().motor_torque().isZero());
}

TEST(FalconSimFirmware, ScriptedFaults) {
  SimTransport t;
  t.open();
  Packet in{};
  t.firmware().drop_answers(2);
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::no_answer);
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::no_answer);
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::ok);
  t.firmware().corrupt_answers(1);
  ASSERT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::ok);
  DeviceReport r{};
  EXPECT_EQ(decode_report(in, r), FrameError::bad_nibble);
  Packet bad = encode_command({{4000, 4000, 4000}, 0});
  bad[3] = 0;
  (void)t.exchange(bad, in);
  EXPECT_EQ(t.firmware().commands_refused(), 1u);
  EXPECT_TRUE(t.firmware().motor_torque().isZero());
  t.firmware().unplug();
  EXPECT_EQ(t.exchange(encode_command({}), in).status, ExchangeStatus::disconnected);
}

}  // namespace
}  // namespace saw::drivers::falcon
