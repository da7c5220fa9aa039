// The dvrk_arm device's cycle (the handshake, homing, servo_cf and servo_cp forwarded, commands
// held while the arm is busy, refusals, the watchdog, move_cp/move_jp/free and measured_js, a FAULT when the
// arm leaves ENABLED and the enable after it, the safe command each time) allocates, locks, waits and prints
// nothing: checked by the RT guard on every cycle.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "fake_dvrk_import.hpp"
#include "guard_support.hpp"
#include "saw/drivers/dvrk/dvrk_arm.hpp"
#include "saw/manager.hpp"

namespace {

using namespace saw;
using namespace saw::drivers::dvrk;

void run_arm(ArmKind kind) {
  DvrkArmConfig c;
  c.kind = kind;
  c.safe_command = kind == ArmKind::psm ? SafeCommand::hold : SafeCommand::zero_wrench;
  c.home = true;
  for (const char* n : {"x", "y", "z", "rx", "ry", "rz"}) c.joints.push_back(JointLimits{n, -1, 1, 0.5});
  saw::testing::GuardWindow window;
  drivers::dvrk::testing::FakeImport import("import");
  import.record = false;  // counted only: the fake must not allocate in the arm's cycle either
  import.pose.position = {0.01, 0, -0.1};
  import.js.size = 6;
  DvrkArm arm("arm", TaskConfig::periodic(std::chrono::milliseconds(1), 0), c);
  Manager manager;
  manager.add(import);
  manager.add(arm);
  manager.connect("arm", "dvrk", "import", "dvrk");
  manager.start_stepped();
  Command* state_command = arm.provided("arm")->find_command("state_command");
  Command* servo = arm.provided("arm")->find_command(kind == ArmKind::psm ? "servo_cp" : "servo_cf");
  StateCommand enable = StateCommand::enable;
  state_command->execute(&enable);
  TimeNs t = 0;
  Pose p = import.pose;
  double base = p.position[0];
  int from = 0;
  constexpr int cycles = 1000;
  for (int i = 0; i < cycles; ++i) {
    if (i == 400) import.state.is_busy = true;
    if (i == 450) import.state.is_busy = false;
    if (i == 600) import.state.state = OperatingStateValue::disabled;  // FAULT, the safe command
    if (i == 650) import.state.state = OperatingStateValue::enabled;
    if (i == 700) state_command->execute(&enable);  // homes again, then follows
    // Silences: the watchdog's safe command; and across the FAULT, after which a client starts
    // again from where the arm is (a jump from there is refused, as it should be).
    // (From the second cycle: before the first sample a pose is a jump from nothing, refused.)
    const bool commanding = i > 0 && (i < 500 || i > 550) && (i < 600 || i > 720);
    if (i == 720) {
      base = import.pose.position[0];
      from = i;
    }
    if (commanding && kind == ArmKind::psm) {
      p.position[0] = base + 0.002 * std::sin((i - from) * 0.01);
      if (i == 300) p.position[0] = NAN;  // refused
      servo->execute(&p);
    } else if (commanding) {
      Wrench w;
      w.force = {0.5 * std::sin(i * 0.01), 0, i == 300 ? 99.0 : 0.0};  // 99 N: refused
      servo->execute(&w);
    }
    // Moves in the silence (the arm driven, no servo command): checked and sent in the cycle.
    if (i == 510) arm.provided("arm")->find_command("move_cp")->execute(&import.pose);
    if (i == 520) arm.provided("arm")->find_command("move_jp")->execute(&import.js);
    if (i == 530 && kind == ArmKind::mtm) arm.provided("arm")->find_command("free")->execute(nullptr);
    import.publish(t);
    manager.step_until(t);
    t += 1'000'000;
  }
  manager.stop();
  const auto counts = window.counts();
  EXPECT_TRUE(arm.following());
  EXPECT_EQ(arm.device_status().faults, 1u);
  const auto& refused = arm.device_status().refused;
  EXPECT_EQ(refused.total(), 1u) << refused.not_finite << " not finite, " << refused.over_limit
                                 << " over a limit, " << refused.wrong_mode << " wrong mode";
  EXPECT_GE(arm.watchdog_trips(), 1u);
  EXPECT_GT(import.count(kind == ArmKind::psm ? "servo_cp" : "servo_cf"), 500);
  EXPECT_GE(arm.summary().safe_commands, 3u) << "refusal, watchdog, fault";
  EXPECT_GT(arm.summary().held_busy, 0u);
  EXPECT_EQ(arm.summary().moves, kind == ArmKind::mtm ? 3u : 2u);
  EXPECT_EQ(counts.cycles, static_cast<std::uint64_t>(cycles));
  EXPECT_RT_CLEAN(counts);
}

TEST(RtGuard, DvrkMtmCycleIsRtClean) { run_arm(ArmKind::mtm); }
TEST(RtGuard, DvrkPsmCycleIsRtClean) { run_arm(ArmKind::psm); }

}  // namespace
