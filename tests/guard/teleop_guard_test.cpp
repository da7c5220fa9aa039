// The teleoperation task (law, ratchet, Ruckig offsets, prediction, every command it takes, its
// FAULT and recovery) and the delay task do none of what the guard counts, from the first cycle.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "guard_support.hpp"
#include "saw/teleop/laws/position_position.hpp"
#include "saw/testing/teleop_rig.hpp"

namespace {

using namespace std::chrono_literals;
using saw::OperatingStateValue;
using saw::StateCommand;

TEST(RtGuard, TeleoperationCycleIsRtClean) {
  saw::testing::GuardWindow window;
  saw::testing::CollaborativeTeleopConfig c;
  c.limits = {2, 2};  // low: the ratchet and the Ruckig offset trajectory both run
  c.prediction = {true, 0.02};
  c.align = true;
  c.stale_timeout = 0.1;
  saw::testing::DelayedTeleopRig rig(c, 0.02);
  bool ratcheted = false;
  for (int i = 0; i < 1000; ++i) {
    rig.master.position[0] = 0.1 * std::sin(i * 0.01);
    rig.master.velocity[0] = 10 * std::cos(i * 0.01) * 0.01;
    if (i == 300) rig.master.press_clutch(true);
    if (i == 400) rig.master.press_clutch(false);
    rig.step();
    bool r = false;
    (void)rig.teleop.state_table().read_latest(rig.teleop.columns().ratcheting, r);
    ratcheted = ratcheted || r;
  }
  rig.manager.stop();
  const auto counts = window.counts();
  EXPECT_TRUE(ratcheted) << "the scenario should have exercised the ratchet";
  EXPECT_EQ(counts.cycles, 2000u);
  EXPECT_RT_CLEAN(counts);
}

// The second law on the same task: its step, hold and reset, and its own commands, from the
// first cycle.
class PpConsole : public saw::Task {
 public:
  PpConsole() : Task("console", saw::TaskConfig::periodic(1ms, 0)) {
    auto& r = require("teleop");
    r.add_function("set_scale", scale_);
    r.add_function("set_stiffness", stiffness_);
  }
  void run() override {
    const int cycle = cycle_++;
    if (cycle == 100) (void)scale_(2.0);
    if (cycle == 150) (void)stiffness_(50.0);
    if (cycle == 160) (void)stiffness_(-1.0);  // refused
  }

 private:
  int cycle_ = 0;
  saw::FunctionWrite<double> scale_, stiffness_;
};

TEST(RtGuard, PositionPositionLawIsRtClean) {
  saw::testing::GuardWindow window;
  saw::teleop::TeleopConfig c;
  c.stale_timeout = 0.1;
  saw::testing::TeleopRig<PpConsole> rig(c, saw::teleop::law_spec<saw::teleop::PositionPositionLaw>());
  for (int i = 0; i < 400; ++i) {
    rig.master.position[0] = 0.1 * std::sin(i * 0.01);
    if (i == 200) rig.master.press_clutch(true);
    if (i == 250) rig.master.press_clutch(false);
    rig.step();
  }
  rig.manager.stop();
  const auto counts = window.counts();
  EXPECT_EQ(rig.teleop.rejected_commands(), 1u);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
  EXPECT_EQ(counts.cycles, 2 * 400u);
  EXPECT_RT_CLEAN(counts);
}

// Sends the teleoperation task every command it takes, valid and invalid, from an RT task; or,
// not `scripted`, only an enable at cycle `enable_at`.
class Console : public saw::Task {
 public:
  explicit Console(bool scripted, int enable_at = -1)
      : Task("console", saw::TaskConfig::periodic(1ms, 0)), scripted_(scripted), enable_at_(enable_at) {
    auto& r = require("teleop");
    r.add_function("state_command", state_);
    r.add_function("set_scale", scale_);
    r.add_function("set_gains", gains_);
    r.add_function("set_force_limits", limits_);
    r.add_function("set_prediction", prediction_);
    r.add_function("set_offset_limits", offset_limits_);
    r.add_function("set_slave_offset", offset_);
    r.add_event_handler_write<saw::OperatingState>("operating_state", [this](const saw::OperatingState& s) {
      if (seen_ < states_.size()) states_[seen_++] = s.state;
    });
  }
  void run() override {
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    const int cycle = cycle_++;
    if (!scripted_) {
      if (cycle == enable_at_) send(state_(StateCommand::enable));
      return;
    }
    switch (cycle) {
      case 10:
        return send(scale_(2.0));  // a rescale while enabled
      case 20:
        return send(gains_(saw::teleop::Gains{50, 50}));
      case 30:
        return send(limits_(saw::teleop::ForceLimits{2, 2}));
      case 40:
        return send(prediction_(saw::teleop::Prediction{true, 0.01, 0.01}));
      case 45:  // new limits for the offset's trajectory (on its way next cycle)
        return send(offset_limits_(saw::teleop::OffsetLimits{0.1, 1.0, 20.0}));
      case 50:
        return send(offset_(saw::Vec3{0.01, 0, 0}));
      case 60:
        return send(state_(StateCommand::pause));
      case 70:
        return send(scale_(1.5));  // a rescale while paused
      case 80:
        return send(state_(StateCommand::resume));
      case 90:
        return send(state_(StateCommand::disable));
      case 100:
        return send(state_(StateCommand::enable));
      case 110:
        return send(state_(StateCommand::home));
      case 120:  // every command refused by validation
        send(scale_(nan));
        send(gains_(saw::teleop::Gains{-1, 50}));
        send(limits_(saw::teleop::ForceLimits{nan, 2}));
        send(prediction_(saw::teleop::Prediction{true, 5.0, 0}));
        send(offset_limits_(saw::teleop::OffsetLimits{50.0, 1.0, 20.0}));
        return send(offset_(saw::Vec3{nan, 0, 0}));
      case 130:  // rescale and re-enable in one cycle
        send(scale_(1.0));
        return send(state_(StateCommand::enable));
      default:
        return;
    }
  }
  std::array<OperatingStateValue, 8> states_{};
  std::size_t seen_ = 0;
  int sent_ = 0, failed_ = 0;

 private:
  void send(saw::Status s) noexcept { s == saw::Status::ok ? ++sent_ : ++failed_; }
  bool scripted_;
  int enable_at_;
  int cycle_ = 0;
  saw::FunctionWrite<StateCommand> state_;
  saw::FunctionWrite<double> scale_;
  saw::FunctionWrite<saw::teleop::Gains> gains_;
  saw::FunctionWrite<saw::teleop::ForceLimits> limits_;
  saw::FunctionWrite<saw::teleop::Prediction> prediction_;
  saw::FunctionWrite<saw::teleop::OffsetLimits> offset_limits_;
  saw::FunctionWrite<saw::Vec3> offset_;
};

// The shared rig with the master moving along a slow sine, period after period.
struct ConsoleRig : saw::testing::TeleopRig<Console> {
  using saw::testing::TeleopRig<Console>::TeleopRig;
  void run(int cycles, bool master_publishes = true) {
    for (int i = 0; i < cycles; ++i, ++t) {
      master.position = {0.05 + 0.02 * std::sin(t * 0.01), 0.02, 0};
      step(1, master_publishes);
    }
  }
  int t = 0;
};

TEST(RtGuard, EveryTeleoperationCommandIsRtClean) {
  saw::testing::GuardWindow window;
  saw::testing::CollaborativeTeleopConfig c;
  c.stale_timeout = 0.1;
  ConsoleRig rig(c, /*scripted=*/true);
  rig.run(200);
  rig.manager.stop();
  const auto counts = window.counts();
  EXPECT_EQ(rig.op.failed_, 0) << "every command should have been queued";
  EXPECT_EQ(rig.op.sent_, 20);
  EXPECT_GE(rig.teleop.rejected_commands(), 6u) << "the invalid commands should have been refused";
  ASSERT_EQ(rig.op.seen_, 4u);  // the last enable finds it enabled: no change, no event
  EXPECT_EQ(rig.op.states_[0], OperatingStateValue::paused);
  EXPECT_EQ(rig.op.states_[1], OperatingStateValue::enabled);
  EXPECT_EQ(rig.op.states_[2], OperatingStateValue::disabled);
  EXPECT_EQ(rig.op.states_[3], OperatingStateValue::enabled);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
  EXPECT_EQ(counts.cycles, 2 * 200u);
  EXPECT_RT_CLEAN(counts);
}

// A master that stops publishing: FAULT, cycles in FAULT, then re-enabled once it is back.
TEST(RtGuard, TeleoperationFaultAndRecoveryAreRtClean) {
  saw::testing::GuardWindow window;
  saw::testing::CollaborativeTeleopConfig c;
  c.stale_timeout = 0.01;
  ConsoleRig rig(c, /*scripted=*/false, /*enable_at=*/200);
  rig.run(50);
  ASSERT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
  rig.run(100, /*master_publishes=*/false);
  const auto stopped = rig.teleop.operating_state();
  rig.run(50);  // the master is back; the teleoperation stays in FAULT until enabled
  const auto back = rig.teleop.operating_state();
  rig.run(50);  // the console enables at its cycle 200
  rig.manager.stop();
  const auto counts = window.counts();
  EXPECT_EQ(stopped, OperatingStateValue::fault);
  EXPECT_EQ(back, OperatingStateValue::fault);
  EXPECT_EQ(rig.teleop.operating_state(), OperatingStateValue::enabled);
  EXPECT_EQ(counts.cycles, 2 * 250u);
  EXPECT_RT_CLEAN(counts);
}

}  // namespace
