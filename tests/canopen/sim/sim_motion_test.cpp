// The simulated drive as a CiA 402 servo: the state machine walked by the protocol library's
// controller over PDOs at 1 kHz, the mode hand-over, CSP following a ramp, CSV, CST's torque
// sign and size, software position limits, quick stop.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sim_master.hpp"

namespace saw::canopen::sim {
namespace {

using namespace testing;
namespace obj = cia402::object;
constexpr double two_pi = 2 * std::numbers::pi;
constexpr double counts_per_rad = 4096 / two_pi;  // sim_drive.eds: 4096 increments per motor revolution

TEST(SimDriveMotion, TheControllerWalksTheDriveToOperationEnabledOverPdos) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csp);
  std::vector<cia402::State> states;
  const auto watch = b.each_tick;
  b.each_tick = [&] {
    watch();
    if (states.empty() || states.back() != b.drive.drive_state()) states.push_back(b.drive.drive_state());
  };
  m.enable();
  ASSERT_TRUE(b.run_until([&] { return m.last.progress == cia402::Progress::reached; }, 200 * ms));
  const std::vector<cia402::State> walk = {cia402::State::switch_on_disabled,
                                           cia402::State::ready_to_switch_on, cia402::State::switched_on,
                                           cia402::State::operation_enabled};
  EXPECT_EQ(states, walk);
  EXPECT_EQ(cia402::decode_state(m.statusword), cia402::State::operation_enabled);
  EXPECT_NE(m.statusword & cia402::statusword::mode_specific_12, 0) << "CSP: the drive follows the target";
  EXPECT_NE(m.statusword & cia402::statusword::voltage_enabled, 0);
  EXPECT_EQ(m.mode_display, static_cast<std::int8_t>(cia402::csp));
  EXPECT_TRUE(m.reach(cia402::Target::switch_on_disabled));
  EXPECT_EQ(b.drive.drive_state(), cia402::State::switch_on_disabled);
}

TEST(SimDriveMotion, ModeOfOperationIsShownAfterTheDrivesNextCycle) {
  Bench b;
  b.tick();
  EXPECT_EQ(b.drive.mode_display(), cia402::csp) << "sim_drive.eds's 0x6060 at power-on";
  b.write(obj::modes_of_operation, DataType::integer8, static_cast<std::int8_t>(cia402::cst));
  EXPECT_EQ(b.upload_value<std::int8_t>(obj::modes_of_operation_display, DataType::integer8),
            static_cast<std::int8_t>(cia402::cst));
  const SdoResult r = b.download(obj::modes_of_operation, DataType::integer8, std::int8_t{1});
  EXPECT_EQ(r.abort, SdoAbort::value_too_low) << "sim_drive.eds limits 0x6060 to 8..10";
  EXPECT_EQ(b.drive.mode_display(), cia402::cst);
}

TEST(SimDriveMotion, CspFollowsARampWithABoundedFollowingError) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csp);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  // 0.2 output revolutions per second for half a second: 20 motor revolutions per second.
  constexpr double speed = 20 * 4096;  // counts/s
  const TimeNs start = b.now + 10 * ms;
  const TimeNs stop = start + 500 * ms;
  m.before_send = [&] {
    const TimeNs t = std::clamp(b.now, start, stop) - start;
    m.target_position = static_cast<std::int32_t>(std::llround(speed * static_cast<double>(t) * 1e-9));
  };
  double worst = 0, worst_settled = 0;
  const auto cycle = b.each_tick;
  b.each_tick = [&] {
    cycle();
    const double e = std::abs(b.drive.following_error_counts());
    worst = std::max(worst, e);
    if (b.now > start + 100 * ms && b.now < stop) worst_settled = std::max(worst_settled, e);
  };
  b.run_for(800 * ms);
  const double travel = speed * 0.5;
  RecordProperty("csp_worst_following_error_counts", std::to_string(worst));
  RecordProperty("csp_settled_following_error_counts", std::to_string(worst_settled));
  EXPECT_LT(worst, 250) << "about 0.05 motor revolutions behind, starting at 20 rev/s at once (195 here)";
  EXPECT_LT(worst_settled, 20) << "velocity feed-forward and the integral: a few counts on the ramp";
  EXPECT_NEAR(m.position, travel, 2) << "at rest on the end point";
  EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled)
      << "no following error fault (window 2000)";
  EXPECT_NEAR(b.drive.motor().position() * counts_per_rad, travel, 2);
}

TEST(SimDriveMotion, CsvReachesTheTargetVelocity) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csv);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.target_velocity = 10 * 4096;  // 10 motor revolutions per second
  b.run_for(200 * ms);
  EXPECT_NEAR(m.velocity, 40960, 40960 * 0.01);
  EXPECT_NEAR(b.drive.motor().velocity(), 10 * two_pi, 10 * two_pi * 0.01);
}

TEST(SimDriveMotion, CstTorqueGivesAnAccelerationOfItsSignAndSize) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::cst);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  const double rated = 0.318;  // N·m, 0x6076 in sim_drive.eds
  const double inertia = b.drive.motor().inertia();
  const auto accelerate = [&](std::int16_t per_mille) {
    m.target_torque = per_mille;
    b.run_for(3 * ms);  // the RPDO's SYNC latency
    const double v0 = b.drive.motor().velocity();
    b.run_for(10 * ms);
    return (b.drive.motor().velocity() - v0) / 0.010;
  };
  const double up = accelerate(200);
  const double expected = 0.2 * rated / inertia;
  EXPECT_GT(up, 0);
  EXPECT_NEAR(up, expected, expected * 0.1) << "τ/J less a little viscous friction";
  EXPECT_NEAR(m.torque, 200, 1) << "0x6077 in per mille of the rated torque";
  const double down = accelerate(-200);
  EXPECT_LT(down, 0);
  EXPECT_NEAR(down, -expected, expected * 0.1);
}

TEST(SimDriveMotion, SoftwarePositionLimitsHoldTheAxisAndSayWhy) {
  Bench b;
  Master m(b);
  b.tick();
  b.write({0x607D, 2}, DataType::integer32, std::int32_t{5000});
  m.start(cia402::csp);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.before_send = [&] { m.target_position = std::min<std::int32_t>(m.target_position + 100, 20000); };
  b.run_for(400 * ms);
  EXPECT_NEAR(m.position, 5000, 2);
  EXPECT_NE(m.statusword & cia402::statusword::internal_limit_active, 0);
  EXPECT_EQ(b.drive.drive_state(), cia402::State::operation_enabled);
}

TEST(SimDriveMotion, QuickStopStopsTheMotorThenDisables) {
  Bench b;
  Master m(b);
  b.tick();
  m.start(cia402::csv);
  ASSERT_TRUE(m.reach(cia402::Target::operation_enabled));
  m.target_velocity = 20 * 4096;
  b.run_for(200 * ms);
  ASSERT_GT(b.drive.motor().velocity(), 100);
  m.controller.set_target(cia402::Target::quick_stop, b.now);
  ASSERT_TRUE(
      b.run_until([&] { return b.drive.drive_state() == cia402::State::quick_stop_active; }, 10 * ms));
  ASSERT_TRUE(
      b.run_until([&] { return b.drive.drive_state() == cia402::State::switch_on_disabled; }, 200 * ms))
      << "option code 2: stop, then switch on disabled";
  EXPECT_LT(std::abs(b.drive.motor().velocity()), two_pi * 0.01);
}

}  // namespace
}  // namespace saw::canopen::sim
