// The device contract, as every driver must keep it (instantiated per driver: *_rig.cpp).
#include "conformance.hpp"

#include <gtest/gtest.h>

namespace saw::conformance {
namespace {

std::unique_ptr<Rig> started(const Driver& d) {
  auto rig = d.make();
  rig->start();
  return rig;
}

// The driver's command, taken: else nothing below means anything.
TEST_P(DeviceConformance, AGoodCommandReachesTheHardware) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  EXPECT_EQ(rig->output(), 0) << "enabled, no command yet: the safe output";
  rig->send(Command::good);
  rig->settle();
  EXPECT_GT(rig->output(), 0);
  EXPECT_FALSE(rig->device().device_status().safe_output);
}

TEST_P(DeviceConformance, NonFiniteCommandsNeverReachTheHardware) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  const double kept = rig->holds() ? rig->output() : 0;
  rig->send(Command::not_finite);
  rig->settle();
  EXPECT_EQ(rig->output(), kept) << "refused; the last good one is kept only by a device that holds";
  rig->send(Command::infinite);
  rig->settle();
  EXPECT_EQ(rig->output(), kept);
  EXPECT_EQ(rig->device().device_status().refused.not_finite, 2u);
  rig->send(rig->holds() ? Command::other : Command::good);
  rig->settle();
  EXPECT_GT(rig->output(), 0) << "a good command after a bad one is applied";
  if (rig->holds()) {
    EXPECT_NE(rig->output(), kept) << "a good command after a bad one is applied";
  }
}

TEST_P(DeviceConformance, OverLimitCommandsNeverReachTheHardware) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  const double kept = rig->holds() ? rig->output() : 0;
  rig->send(Command::over_limit);
  rig->settle();
  EXPECT_EQ(rig->output(), kept) << "refused; the last good one is kept only by a device that holds";
  EXPECT_EQ(rig->device().device_status().refused.over_limit, 1u);
}

TEST_P(DeviceConformance, WhenCommandsStopTheHardwareIsSafeWithinTheTimeout) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  const TimeNs timeout = rig->device().contract().command_timeout;
  const int cycles = static_cast<int>(timeout / rig->period());
  rig->send(Command::good);
  rig->cycle();  // handled: the timeout counts from this cycle
  rig->cycle(cycles - 1);
  EXPECT_GT(rig->output(), 0) << "still fresh";
  const double kept = rig->holds() ? rig->output() : 0;
  rig->cycle(2);
  rig->settle();
  EXPECT_EQ(rig->output(), kept) << "no command for longer than command_timeout: the safe output, or held";
  EXPECT_EQ(rig->device().watchdog_trips(), 1u);
  EXPECT_TRUE(rig->device().watchdog().holding());
  rig->send(rig->holds() ? Command::other : Command::good);
  rig->settle();
  EXPECT_GT(rig->output(), 0) << "a fresh command drives again";
  if (rig->holds()) {
    EXPECT_NE(rig->output(), kept) << "a fresh command drives again";
  }
  EXPECT_FALSE(rig->device().watchdog().holding());
}

TEST_P(DeviceConformance, DisableIsTheSafeStateAndCommandsWaitForEnable) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  rig->state_command(StateCommand::disable);
  rig->settle();
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::disabled);
  EXPECT_TRUE(rig->safe());
  rig->send(Command::good);
  rig->settle();
  EXPECT_EQ(rig->output(), 0) << "disabled: no command reaches the hardware";
  ASSERT_TRUE(rig->enable());
  rig->settle();
  EXPECT_EQ(rig->output(), 0) << "a command sent while disabled is not applied after enable";
}

TEST_P(DeviceConformance, PauseTakesTheSafeOutputAndResumeGivesItBack) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->state_command(StateCommand::pause);
  rig->send(Command::good);
  rig->settle();
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::paused);
  EXPECT_EQ(rig->output(), 0);
  rig->state_command(StateCommand::resume);
  rig->send(Command::good);
  rig->settle();
  EXPECT_EQ(rig->device().operating_state().state, OperatingStateValue::enabled);
  EXPECT_GT(rig->output(), 0);
}

TEST_P(DeviceConformance, AFailingHardwareFaultsSayingWhyAndIsSafe) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  if (!rig->break_hardware())
    GTEST_SKIP() << GetParam().name << "'s simulated hardware has nothing that fails";
  for (int i = 0; i < 1000 && rig->device().operating_state().state != OperatingStateValue::fault; ++i) {
    rig->send(Command::good);  // a commander that goes on: the fault must win
    rig->cycle();
  }
  rig->settle();
  const Device& d = rig->device();
  ASSERT_EQ(d.operating_state().state, OperatingStateValue::fault);
  EXPECT_NE(d.fault().code, FaultCode::none);
  EXPECT_FALSE(d.device_status().reason_text().empty()) << "a FAULT says why";
  EXPECT_EQ(d.device_status().faults, 1u);
  EXPECT_TRUE(rig->safe());
  EXPECT_EQ(rig->output(), 0);
}

// A late loop (the task's deadline policy breached: the periodic loop calls this at the wake-up
// that finds it) is a FAULT naming the figures, through the safe state, whatever the commander does.
TEST_P(DeviceConformance, ALateLoopFaultsSayingHowLateAndIsSafe) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  DeadlineBreach late;
  late.missed = late.periods = 12;
  late.latency = 11'800'000;
  late.period = 1'000'000;
  detail::Access::deadline_breach(rig->device(), late);
  rig->send(Command::good);
  rig->cycle();
  rig->send(Command::good);
  rig->settle();
  const Device& d = rig->device();
  ASSERT_EQ(d.operating_state().state, OperatingStateValue::fault);
  EXPECT_EQ(d.fault().code, FaultCode::deadline_missed);
  EXPECT_EQ(d.fault().detail, 12u);
  EXPECT_NE(to_string(d.fault()).find("12 periods in a row (last wake-up 11.8 ms late)"), std::string::npos)
      << to_string(d.fault());
  EXPECT_TRUE(rig->safe());
  EXPECT_EQ(rig->output(), 0);
}

TEST_P(DeviceConformance, StopLeavesTheHardwareSafe) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  rig->stop();
  EXPECT_TRUE(rig->safe()) << "the simulator saw the safe state before the device let go";
  EXPECT_EQ(rig->output(), 0);
  EXPECT_GE(rig->device().device_status().safe_entries, 1u);
}

// The hardware's own watchdog (a CANopen node's heartbeat consumer): a controller that dies
// without a word leaves hardware that notices and takes its safe state by itself.
TEST_P(DeviceConformance, WhenTheControllerDiesTheHardwareNoticesAndIsSafe) {
  auto rig = started(GetParam());
  ASSERT_TRUE(rig->enable());
  rig->send(Command::good);
  rig->settle();
  ASSERT_GT(rig->output(), 0);
  if (!rig->kill_controller(1'000'000'000))
    GTEST_SKIP() << GetParam().name << "'s simulated hardware does not watch its controller";
  EXPECT_TRUE(rig->safe());
  EXPECT_EQ(rig->output(), 0);
}

TEST_P(DeviceConformance, AFailedStartSaysWhyAndLeavesTheHardwareSafe) {
  auto rig = GetParam().make();
  if (!rig->fail_start()) GTEST_SKIP() << GetParam().name << "'s simulated hardware cannot fail to start";
  std::string message;
  try {
    rig->start();
  } catch (const std::exception& e) {
    message = e.what();
  }
  EXPECT_FALSE(message.empty()) << "the start did not fail";
  EXPECT_TRUE(rig->safe());
  EXPECT_EQ(rig->device().device_status().safe_entries, 1u);
}

}  // namespace
}  // namespace saw::conformance
