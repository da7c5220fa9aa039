// DvrkArm against a scripted stand-in for the gateway's import of a dVRK arm, on the stepped
// clock: the dVRK's handshake before any motion, a FAULT for each way the arm can go wrong, and
// the safe command on each stop path, once.
#include "saw/drivers/dvrk/dvrk_arm.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "dvrk_test_rig.hpp"
#include "saw/component.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/deploy/deployment.hpp"
#include "saw/drivers/dvrk/registration.hpp"
#include "saw/manager.hpp"

namespace saw::drivers::dvrk {
namespace {

using testing::enable_mtm;
using testing::FakeImport;
using testing::mtm;
using testing::psm;
using testing::Rig;

// A PSM's jaw goes with its pose, checked; an MTM's gripper is read through.
TEST(DvrkArm, APsmsJawFollowsWithItsPoseWithinItsLimitsAndAnMtmsGripperIsRead) {
  Rig r(psm());
  r.import.pose.position = {0.01, 0, -0.1};
  auto jaw = [&](double angle) {
    JointState j;
    j.size = 1;
    j.position[0] = angle;
    r.arm.provided("arm")->find_command("jaw_servo_jp")->execute(&j);
  };
  jaw(0.5);
  r.step(2);
  EXPECT_EQ(r.import.count("jaw_servo_jp"), 0) << "not before the arm is driven";
  r.state_command(StateCommand::enable);
  r.step(40);
  ASSERT_TRUE(r.arm.following());
  Pose p = r.import.pose;
  for (const double angle : {0.6, 2.0, std::nan(""), -1.0, 0.7}) {
    jaw(angle);
    p.position[0] += 0.0001;
    r.servo_cp(p);
    r.step();
  }
  EXPECT_EQ(r.import.count("jaw_servo_jp"), 2) << "0.6 and 0.7; 2 rad, NaN and -1 rad refused";
  EXPECT_EQ(r.import.received.back().what, "jaw_servo_jp");
  EXPECT_EQ(r.import.received.back().jaw, 0.7);
  EXPECT_EQ(r.arm.summary().jaw_refused, 3u);
  r.import.state.is_busy = true;  // held back with the pose
  r.step();
  jaw(0.8);
  r.servo_cp(p);
  r.step(2);
  EXPECT_EQ(r.import.count("jaw_servo_jp"), 2);

  Rig m(mtm());
  m.import.jaw = 0.3;
  m.step(2);
  JointState g;
  const auto* gripper = m.arm.provided("arm")->find_command("gripper_measured_js");
  ASSERT_NE(gripper, nullptr);
  ASSERT_EQ(gripper->read(nullptr, &g), Status::ok);
  EXPECT_EQ(g.size, 1u);
  EXPECT_EQ(g.position[0], 0.3) << "the import's gripper, read through";
  EXPECT_EQ(m.arm.provided("arm")->find_command("jaw_servo_jp"), nullptr) << "an MTM has no jaw";
}

// The console's clutch, as the teleoperation takes it from its master: the arm's event.
TEST(DvrkArm, TheConsolesClutchIsTheArmsEvent) {
  struct Observer : Component {
    Observer() : Component("observer") {
      crtk::require(require("arm"), crtk::arm::clutch,
                    [this](const ButtonEvent& b) { seen.push_back(b.pressed); });
    }
    std::vector<bool> seen;
  } observer;
  FakeImport import{"import"};
  DvrkArm arm("arm", TaskConfig::periodic(std::chrono::milliseconds(1), 0), mtm());
  Manager manager;
  manager.add(import);
  manager.add(arm);
  manager.add(observer);
  manager.connect("arm", "dvrk", "import", "dvrk");
  manager.connect("observer", "arm", "arm", "arm");
  manager.start_stepped();
  TimeNs t = 0;
  const auto step = [&] {
    import.publish(t);
    manager.step_until(t);
    t += 1'000'000;
  };
  step();
  import.clutch(true);
  step();
  step();
  import.clutch(false);
  step();
  step();
  manager.stop();
  EXPECT_EQ(observer.seen, (std::vector<bool>{true, false}));
}

TEST(DvrkArm, NothingButStateCommandsReachTheArmBeforeItIsEnabledHomedAndIdle) {
  Rig r(mtm());
  r.step(3);
  enable_mtm(r);
  ASSERT_GE(r.import.received.size(), 2u);
  EXPECT_EQ(r.import.received[0].what, "enable");
  EXPECT_EQ(r.import.received[1].what, "home");
  EXPECT_EQ(r.import.received[1].arm.state, OperatingStateValue::enabled) << "home only once ENABLED";
  EXPECT_EQ(r.import.count("enable"), 1) << "sent once, not every cycle";
  EXPECT_EQ(r.import.count("home"), 1);
  for (const auto& x : r.import.received)
    if (x.what == "servo_cf" &&
        !(x.arm.state == OperatingStateValue::enabled && x.arm.is_homed && !x.arm.is_busy))
      ADD_FAILURE() << "a wrench reached the arm while it was " << static_cast<int>(x.arm.state)
                    << (x.arm.is_homed ? " homed" : " not homed") << (x.arm.is_busy ? " busy" : "");
  const int before = r.import.count("servo_cf");
  for (int i = 0; i < 5; ++i) {
    r.servo_cf({0.5, 0, 0});
    r.step();
  }
  EXPECT_EQ(r.import.count("servo_cf"), before + 5);
  EXPECT_EQ(r.import.received.back().wrench.force[0], 0.5);
  EXPECT_TRUE(r.import.received.back().arm.is_homed);
}

// A reliable writer still matched to a reader that is gone (the dVRK restarted) loses what it
// sends: an enable or home with no effect is sent again after 1 s, the arm idle.
TEST(DvrkArm, ALostEnableOrHomeIsSentAgain) {
  DvrkArmConfig c = mtm();
  c.contract.enable_timeout = 5'000'000'000;
  for (const int lost : {1, 2}) {  // enables lost
    Rig r(c);
    r.import.lose_state_commands = lost;
    r.state_command(StateCommand::enable);
    r.step(900);
    EXPECT_EQ(r.import.count("enable"), 1) << "not again within the second";
    r.step(1100 * lost);
    EXPECT_TRUE(r.arm.following()) << lost << " lost: state " << static_cast<int>(r.state());
    EXPECT_EQ(r.import.count("enable"), lost + 1);
    EXPECT_EQ(r.import.count("home"), 1);
  }
  Rig r(c);  // enabled, not homed: the home lost
  r.import.state = {OperatingStateValue::enabled, false, false};
  r.import.lose_state_commands = 1;
  r.step(2);
  r.state_command(StateCommand::enable);
  r.step(1200);
  EXPECT_TRUE(r.arm.following());
  EXPECT_EQ(r.import.count("enable"), 0);
  EXPECT_EQ(r.import.count("home"), 2);
  EXPECT_EQ(r.arm.summary().state_commands, 2u);
}

TEST(DvrkArm, AnArmNotHomedIsRefusedUnlessTheDeploymentLetsItHome) {
  Rig r(mtm(/*home=*/false));
  r.state_command(StateCommand::enable);
  r.step(20);
  EXPECT_EQ(r.state(), OperatingStateValue::fault);
  EXPECT_EQ(r.arm.fault().code, FaultCode::device_disabled);
  EXPECT_EQ(r.import.count("home"), 0) << "homing moves the arm: never unasked";
}

TEST(DvrkArm, AnArmInFaultIsNotEnabledButSaidToBeClearedAtItsConsole) {
  Rig r(mtm());
  r.import.state = {OperatingStateValue::fault, true, false};
  r.step(2);
  r.state_command(StateCommand::enable);
  r.step(5);
  EXPECT_EQ(r.state(), OperatingStateValue::fault);
  EXPECT_EQ(r.arm.fault().code, FaultCode::device_fault);
  EXPECT_EQ(r.import.count("enable"), 0) << "the dVRK ignores an enable in FAULT until a disable";
}

TEST(DvrkArm, AnArmAlreadyEnabledAndHomedIsFollowedWithoutACommand) {
  Rig r(mtm(/*home=*/false));
  r.import.state = {OperatingStateValue::enabled, true, false};
  r.step(2);
  enable_mtm(r);
  EXPECT_EQ(r.import.count("enable"), 0);
  EXPECT_EQ(r.import.count("home"), 0);
}

TEST(DvrkArm, AnArmThatLeavesEnabledFaultsTheDeviceAndGetsOneZeroWrench) {
  Rig r(mtm());
  enable_mtm(r);
  r.servo_cf({1, 0, 0});
  r.step();
  r.import.state.state = OperatingStateValue::disabled;  // the dVRK's console powered it off
  for (int i = 0; i < 10; ++i) {
    r.servo_cf({1, 0, 0});
    r.step();
  }
  EXPECT_EQ(r.state(), OperatingStateValue::fault);
  EXPECT_EQ(r.arm.fault().code, FaultCode::device_disabled);
  const auto& last = r.import.received.back();
  EXPECT_EQ(last.what, "servo_cf");
  EXPECT_EQ(last.wrench.force[0], 0.0) << "the safe command is the last thing sent";
  EXPECT_EQ(r.arm.summary().safe_commands, 1u) << "once, not every cycle";
}

TEST(DvrkArm, AnArmInFaultOrUnhomedFaultsTheDevice) {
  for (const bool fault : {true, false}) {
    Rig r(mtm());
    enable_mtm(r);
    if (fault)
      r.import.state.state = OperatingStateValue::fault;
    else
      r.import.state.is_homed = false;
    r.step(3);
    EXPECT_EQ(r.state(), OperatingStateValue::fault);
    EXPECT_EQ(r.arm.fault().code, FaultCode::device_fault);
  }
}

// The dVRK latches its last errors: those from before the arm was driven are not this run's.
TEST(DvrkArm, AnErrorOfTheArmWhileDrivenFaultsTheDevice) {
  Rig r(mtm());
  r.import.errors = 2;
  enable_mtm(r);
  r.servo_cf({0.5, 0, 0});
  r.step(3);
  EXPECT_EQ(r.state(), OperatingStateValue::enabled) << "errors before the enable are not a fault";
  r.import.errors = 3;
  r.step(2);
  EXPECT_EQ(r.state(), OperatingStateValue::fault);
  EXPECT_EQ(r.arm.fault().code, FaultCode::device_error);
  EXPECT_EQ(r.import.received.back().what, "servo_cf");
  EXPECT_EQ(r.import.received.back().wrench.force[0], 0.0) << "the zero wrench";
}

// A pose that is not one (NaN, a quaternion off the unit sphere) is never used: the last good one
// stands, and a stream of them is no stream (stale).
TEST(DvrkArm, APoseThatIsNotOneIsRefusedAndAStreamOfThemGoesStale) {
  DvrkArmConfig c = mtm();
  c.stale_timeout = 20'000'000;
  Rig r(c);
  enable_mtm(r);
  r.import.pose.position[0] = std::nan("");
  int cycles = 0;
  while (r.state() != OperatingStateValue::fault && cycles < 100) {
    r.servo_cf({1, 0, 0});
    r.step();
    ++cycles;
    if (cycles == 5) {
      EXPECT_GE(r.arm.summary().bad_poses, 4u) << "refused, never used";
    }
  }
  EXPECT_EQ(r.arm.fault().code, FaultCode::input_stale);
  EXPECT_GE(cycles, 19);
  EXPECT_LE(cycles, 22);
  r.import.pose.position[0] = 0;
  r.import.pose.orientation = {0, 0, 0, 2};  // not a rotation
  const auto before = r.arm.summary().bad_poses;
  r.step(2);
  EXPECT_EQ(r.arm.summary().bad_poses, before + 2);
  EXPECT_EQ(r.import.received.back().wrench.force[0], 0.0);
}

TEST(DvrkArm, ADvrkThatStopsPublishingFaultsAtTheStaleTimeout) {
  DvrkArmConfig c = mtm();
  c.stale_timeout = 20'000'000;
  Rig r(c);
  enable_mtm(r);
  int cycles = 0;
  while (r.state() != OperatingStateValue::fault && cycles < 100) {
    r.servo_cf({1, 0, 0});
    r.step(1, /*publish=*/false);
    ++cycles;
  }
  EXPECT_EQ(r.arm.fault().code, FaultCode::input_stale);
  EXPECT_GE(cycles, 20);
  EXPECT_LE(cycles, 22);
  EXPECT_EQ(r.import.received.back().wrench.force[0], 0.0);
}

TEST(DvrkArm, WhenCommandsStopTheArmGetsOneZeroWrench) {
  Rig r(mtm());
  enable_mtm(r);
  r.servo_cf({1, 0, 0});
  r.step();
  const auto sent = r.import.received.size();
  r.step(50);  // the teleoperation went silent
  // The last command stands until the watchdog (command_timeout: 3 periods), then one safe
  // command, then nothing.
  ASSERT_GT(r.import.received.size(), sent);
  ASSERT_LE(r.import.received.size(), sent + 4);
  int zeros = 0;
  for (auto i = sent; i < r.import.received.size(); ++i) zeros += r.import.received[i].wrench.force[0] == 0.0;
  EXPECT_EQ(zeros, 1);
  EXPECT_EQ(r.import.received.back().wrench.force[0], 0.0);
  EXPECT_EQ(r.arm.watchdog_trips(), 1u);
  EXPECT_EQ(r.state(), OperatingStateValue::enabled) << "a pause in commands is not a fault";
}

TEST(DvrkArm, MotionIsHeldBackWhileTheArmIsBusy) {
  Rig r(mtm());
  enable_mtm(r);
  r.import.state.is_busy = true;
  r.step();
  const int before = r.import.count("servo_cf");
  for (int i = 0; i < 5; ++i) {
    r.servo_cf({1, 0, 0});
    r.step();
  }
  EXPECT_EQ(r.import.count("servo_cf"), before);
  EXPECT_GE(r.arm.summary().held_busy, 5u);
}

TEST(DvrkArm, APsmFollowsPosesAndHoldsOnDisableAndStop) {
  Rig r(psm());
  r.import.pose.position = {0.01, 0, -0.1};
  r.state_command(StateCommand::enable);
  r.step(40);
  ASSERT_TRUE(r.arm.following());
  Pose p = r.import.pose;
  for (int i = 0; i < 5; ++i) {
    p.position[0] += 0.0001;  // 0.1 mm a cycle: 0.1 m/s
    r.servo_cp(p);
    r.step();
  }
  EXPECT_EQ(r.import.count("servo_cp"), 5);
  EXPECT_NEAR(r.import.received.back().pose.position[0], 0.0105, 1e-12);
  Pose jump = p;
  jump.position[0] += 0.01;  // 1 cm in a cycle
  r.servo_cp(jump);
  r.step();
  EXPECT_EQ(r.import.count("servo_cp"), 5) << "a step faster than max_linear_speed never leaves";
  EXPECT_EQ(r.import.count("hold"), 1) << "the refusal's safe output: hold";
  r.servo_cp(p);
  r.step();
  r.state_command(StateCommand::disable);
  r.step();
  EXPECT_EQ(r.import.count("hold"), 2);
  EXPECT_EQ(r.import.count("other"), 0) << "our disable never powers the dVRK arm off";
}

// The dVRK drops a PSM's Cartesian commands, with a warning and no state, while its tool is not
// past the cannula: goals that take no effect are a FAULT, once they are far for long enough.
TEST(DvrkArm, APsmThatDoesNotFollowItsGoalsFaultsTheDevice) {
  for (const bool follows : {true, false}) {
    SCOPED_TRACE(follows ? "an arm that follows" : "an arm that does not");
    DvrkArmConfig c = psm();
    c.following_error = 0.01;
    c.following_time = 100'000'000;
    Rig r(c);
    r.import.pose.position = {0.0, 0, -0.1};
    r.state_command(StateCommand::enable);
    r.step(40);
    ASSERT_TRUE(r.arm.following());
    r.import.follows = follows;
    Pose p = r.import.pose;
    int far_cycles = 0;
    for (int i = 0; i < 400 && r.state() == OperatingStateValue::enabled; ++i) {
      p.position[0] += 0.00015;  // 0.15 m/s, under the speed limit
      if (std::abs(p.position[0] - r.import.pose.position[0]) > 0.01) ++far_cycles;
      r.servo_cp(p);
      r.step();
    }
    if (follows) {
      EXPECT_EQ(r.state(), OperatingStateValue::enabled) << "an arm that follows never faults";
      continue;
    }
    ASSERT_EQ(r.state(), OperatingStateValue::fault);
    EXPECT_EQ(r.arm.fault().code, FaultCode::device_error);
    EXPECT_NEAR(far_cycles, 100, 3) << "faulted after following_time beyond following_error";
    EXPECT_EQ(r.import.received.back().what, "hold") << "and held";
  }
}

TEST(DvrkArm, APsmWithoutHoldGetsItsMeasuredPose) {
  Rig r(psm(SafeCommand::servo_cp_measured));
  r.import.pose.position = {0.02, 0.01, -0.12};
  r.import.follows = false;
  r.state_command(StateCommand::enable);
  r.step(40);
  ASSERT_TRUE(r.arm.following());
  Pose p = r.import.pose;
  p.position[2] += 0.0001;
  r.servo_cp(p);
  r.step();
  r.import.pose.position[2] = -0.125;  // pushed away from its goal (a collision, a hand)
  r.step(10);                          // commands stop
  const auto& last = r.import.received.back();
  EXPECT_EQ(last.what, "servo_cp");
  EXPECT_EQ(last.pose.position[2], -0.125) << "where it was measured, not the last goal";
  EXPECT_EQ(r.import.count("hold"), 0);
}

TEST(DvrkArm, AWrongKindOfCommandIsRefused) {
  Rig r(psm());
  EXPECT_EQ(r.arm.provided("arm")->find_command("servo_cf"), nullptr) << "a PSM takes poses";
  Rig m(mtm());
  EXPECT_EQ(m.arm.provided("arm")->find_command("servo_cp"), nullptr) << "an MTM takes wrenches";
}

TEST(DvrkArm, AnUnconnectedArmIsAFailedStartSayingWhy) {
  DvrkArm a("alone", TaskConfig::periodic(std::chrono::milliseconds(1), 0), mtm());
  a.state_table().finalize();
  try {
    a.startup();
    ADD_FAILURE() << "started without its import";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("not connected to the arm's import"), std::string::npos) << e.what();
  }
}

// A deployment's mistakes name file, line and key.
TEST(DvrkArmDeployment, ParameterErrorsNameFileLineAndKey) {
  deploy::ComponentRegistry registry;
  register_components(registry);
  const std::string file =
      "deployment: {name: d, clock: stepped}\ncomponents:\n  - name: psm1\n    type: dvrk_arm\n"
      "    task: {period: 1ms}\n    params: ";
  const std::pair<const char*, const char*> cases[] = {
      {"{safe_command: hold}", "key 'components[0].params.kind': say which arm this is: mtm, psm or ecm"},
      {"{kind: sjm}", "key 'components[0].params.kind': 'sjm' is not one of: mtm, psm, ecm"},
      {"{kind: ecm, jaw_max: 1}", "key 'components[0].params.jaw_max'"},
      {"{kind: psm, safe_command: zero_wrench}", "key 'components[0].params.safe_command': a PSM's or ECM's is hold"},
      {"{kind: mtm, safe_command: servo_cp_measured}",
       "key 'components[0].params.safe_command': an MTM's is"},
      {"{kind: mtm, stale_timeout: 1ms}", "key 'components[0].params.stale_timeout': at least three periods"},
      {"{kind: mtm, max_force: 50}", "key 'components[0].params.max_force'"},
      {"{kind: psm, workspace: {min: [0, 0, 0], max: [1, -1, 1]}}",
       "key 'components[0].params.workspace.max': must be above min"},
      {"{kind: mtm, max_linear_speed: 1}", "key 'components[0].params.max_linear_speed': unknown parameter"},
      {"{kind: psm, servo_jp: true}", "key 'components[0].params.servo_jp': needs the arm's joints"},
      {"{kind: psm, following_error: -0.01}", "key 'components[0].params.following_error'"},
      {"{kind: psm, following_time: 20s}", "key 'components[0].params.following_time': at least one period"},
      {"{kind: mtm, following_error: 0.01}", "key 'components[0].params.following_error': unknown parameter"},
      {"{kind: psm, joints: {names: [a, b], min: [0]}}",
       "key 'components[0].params.joints.min': one value per joint (2)"},
      {"{kind: psm, joints: {names: [a], min: [1], max: [0]}}",
       "key 'components[0].params.joints.max': must be above min for a"},
      {"{kind: psm, joints: {names: [a], max_velocity: [0]}}",
       "key 'components[0].params.joints.max_velocity': must be positive for a"},
      {"{kind: psm, joints: {names: [a], mni: [0]}}",
       "key 'components[0].params.joints.mni': unknown parameter"},
  };
  for (const auto& [params, expect] : cases) {
    try {
      (void)deploy::make_deployment(file + params + "\n", "d.yaml", registry, "");
      ADD_FAILURE() << "no error for " << params;
    } catch (const deploy::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind("d.yaml:6:", 0), 0u) << what;
      EXPECT_NE(what.find(expect), std::string::npos) << what << "\nexpected: " << expect;
    }
  }
}

}  // namespace
}  // namespace saw::drivers::dvrk
