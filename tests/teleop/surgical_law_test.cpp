// The surgical law on the teleoperation task, between two fake devices on the stepped clock:
// translation scaled from engagement in the camera frame, orientation absolute once aligned,
// no step in the commanded pose at engagement, clutch or misalignment, the jaw from the gripper.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "saw/teleop/laws/surgical.hpp"
#include "saw/testing/stepper.hpp"
#include "teleop_support.hpp"

namespace {

using saw::teleop::SurgicalLaw;
using saw::testing::dist;

class SurgicalOperator : public saw::Component {
 public:
  SurgicalOperator() : Component("operator") {
    auto& r = require("teleop");
    r.add_function("misalignment", misalignment);
    r.add_function("aligned", aligned);
    r.add_function("orientation_error", orientation_error);
  }
  saw::FunctionRead<double> misalignment, aligned, orientation_error;
};
using Rig = saw::testing::TeleopRig<SurgicalOperator>;

constexpr double deg = std::numbers::pi / 180;

saw::Quat about_z(double degrees) { return {0, 0, std::sin(degrees * deg / 2), std::cos(degrees * deg / 2)}; }
double angle_between(const saw::Quat& a, const saw::Quat& b) {
  const Eigen::Quaterniond qa(a[3], a[0], a[1], a[2]), qb(b[3], b[0], b[1], b[2]);
  return qa.angularDistance(qb) / deg;
}

saw::teleop::TeleopConfig follows_pose() {
  saw::teleop::TeleopConfig c;
  c.slave_servo_cp = true;
  return c;
}

Rig rig_with(const SurgicalLaw::Settings& s) {
  return Rig(follows_pose(), saw::teleop::law_spec<SurgicalLaw>(s));
}

TEST(SurgicalLaw, TranslationIsScaledFromEngagementInTheCameraFrameWithoutAStep) {
  SurgicalLaw::Settings s;
  s.scale = 0.2;
  s.camera_rpy = {0, 0, 90};  // the camera turned a quarter about z: the master's x is the slave's y
  Rig rig = rig_with(s);
  rig.master.position = {0.05, 0.01, 0};
  rig.master.orientation = about_z(-85);  // seen through the camera: 5 degrees from the slave's
  rig.slave.position = {-0.02, 0.03, -0.1};
  rig.step(3);
  ASSERT_GT(rig.slave.goals, 0);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "engaging: no step";
  EXPECT_LT(angle_between(rig.slave.goal.orientation, rig.slave.orientation), 1e-9) << "nor in orientation";
  rig.master.position[0] += 0.01;
  rig.step(20);  // 2 mm at up to max_linear_speed (0.18 mm a cycle)
  EXPECT_NEAR(rig.slave.goal.position[0], -0.02, 1e-12);
  EXPECT_NEAR(rig.slave.goal.position[1], 0.03 + 0.002, 1e-12) << "1 cm along the master's x: 2 mm along y";
  EXPECT_EQ(rig.slave.commands, 0) << "a pose only, never a force";
}

// The camera frame from an endoscope arm: a third device on the task's "camera" interface (the
// law's declared input), its orientation taken at each engagement — a camera moved while
// engaged makes no step; the next engagement (a clutch's release) uses where it is then.
TEST(SurgicalLaw, TheCameraFrameIsTheEndoscopesOrientationTakenAtEachEngagement) {
  saw::testing::FakeDevice master{"master"}, slave{"slave"}, endoscope{"endoscope"};
  SurgicalLaw::Settings s;
  s.scale = 0.2;
  s.camera_rpy = {0, 0, -90};  // not used: the endoscope is connected
  saw::teleop::Teleoperation teleop("teleop", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                    follows_pose(), saw::teleop::law_spec<SurgicalLaw>(s));
  saw::Manager manager;
  for (saw::Component* c : std::initializer_list<saw::Component*>{&master, &slave, &endoscope, &teleop})
    manager.add(*c);
  manager.connect("teleop", "master", "master", "arm");
  manager.connect("teleop", "slave", "slave", "arm");
  manager.connect("teleop", "camera", "endoscope", "arm");
  manager.start_stepped();
  saw::testing::Stepper stepper{manager};
  const auto step = [&](int n) {
    for (int i = 0; i < n; ++i) stepper({&master, &slave, &endoscope});
  };
  endoscope.orientation = about_z(90);  // the master's x is the slave's y
  master.orientation = about_z(-90);
  step(3);
  master.position[0] += 0.01;
  step(20);
  EXPECT_NEAR(slave.goal.position[0], 0.0, 1e-12);
  EXPECT_NEAR(slave.goal.position[1], 0.002, 1e-12) << "through the endoscope's frame, not camera_rpy's";
  endoscope.orientation = about_z(0);  // the camera moved while engaged
  const saw::Vec3 before = slave.goal.position;
  step(2);
  EXPECT_LT(dist(slave.goal.position, before), 1e-12) << "no step: C was taken at engagement";
  slave.position = slave.goal.position;
  slave.orientation = slave.goal.orientation;
  master.press_clutch(true);
  step(2);
  master.orientation = about_z(0);  // aligned again through the new camera frame
  master.press_clutch(false);
  step(3);
  master.position[0] += 0.01;
  step(20);
  EXPECT_NEAR(slave.goal.position[0], before[0] + 0.002, 1e-12) << "the new frame from the next engagement";
  EXPECT_NEAR(slave.goal.position[1], before[1], 1e-12);
  manager.stop();
}

TEST(SurgicalLaw, OrientationFollowsTheMasterOnceAligned) {
  Rig rig = rig_with(SurgicalLaw::Settings{});
  rig.master.orientation = about_z(3);
  rig.step(3);
  rig.master.orientation = about_z(33);
  rig.step(250);  // 30 degrees at up to max_angular_speed (0.15 degrees a cycle)
  EXPECT_NEAR(angle_between(rig.slave.goal.orientation, about_z(30)), 0, 1e-9)
      << "the master turned 30 degrees; the 3 degrees it was off stay an offset";
  double aligned = 0;
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  EXPECT_EQ(aligned, 1.0);
}

TEST(SurgicalLaw, ItRefusesToEngageWhileMisalignedAndEngagesWithoutAStepOnceAligned) {
  Rig rig = rig_with(SurgicalLaw::Settings{});  // align_tolerance 10 degrees
  rig.slave.position = {0, 0, -0.1};
  rig.master.orientation = about_z(30);
  rig.step(3);
  double aligned = 1, off = 0;
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  ASSERT_EQ(rig.op.misalignment(off), saw::Status::ok);
  EXPECT_EQ(aligned, 0.0);
  EXPECT_NEAR(off, 30, 1e-9) << "the operator is told how far off the master is";
  rig.master.position = {0.05, 0, 0};  // moving the misaligned master moves nothing
  rig.step(3);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12);
  EXPECT_LT(angle_between(rig.slave.goal.orientation, rig.slave.orientation), 1e-9);
  rig.master.orientation = about_z(8);  // within the tolerance: engaged, from here
  rig.step(2);
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  EXPECT_EQ(aligned, 1.0);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "no step at engagement";
  EXPECT_LT(angle_between(rig.slave.goal.orientation, rig.slave.orientation), 1e-9);
  rig.master.position[0] += 0.01;
  rig.step(20);
  EXPECT_NEAR(rig.slave.goal.position[0], 0.002, 1e-12);
}

// A master that takes move_cp (the dVRK's MTM) is sent, once at each engagement found
// misaligned, its own position turned to where it is aligned through the camera (C⁻¹ · q_s0);
// no wrench goes to it until it is busy with the move; busy, the task holds; idle there, the law
// engages without a step. With
// align_master false, or while aligned, nothing is sent.
TEST(SurgicalLaw, AMisalignedMasterThatTakesMoveCpIsSentTheAlignedPoseOnceAtEachEngagement) {
  SurgicalLaw::Settings s;
  s.camera_rpy = {0, 0, 90};
  Rig rig = rig_with(s);
  rig.master.position = {0.05, 0.01, 0.02};
  rig.master.orientation = about_z(0);  // seen through the camera: 90 degrees from the slave's
  rig.slave.position = {0, 0, -0.1};
  rig.step(5);
  ASSERT_EQ(rig.master.moves, 1) << "one move, not one a cycle";
  EXPECT_LT(dist(rig.master.move_goal.position, rig.master.position), 1e-12) << "at its position";
  EXPECT_LT(angle_between(rig.master.move_goal.orientation, about_z(-90)), 1e-9) << "turned to C⁻¹ · q_s0";
  double aligned = 1;
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  EXPECT_EQ(aligned, 0.0);
  const int wrenches = rig.master.commands;
  rig.step(3);
  EXPECT_EQ(rig.master.commands, wrenches)
      << "no wrench to the master until it is busy: it would pre-empt the move";
  rig.master.busy = true;  // the move runs: the task holds
  rig.step(3);
  rig.master.orientation = rig.master.move_goal.orientation;
  rig.master.busy = false;
  rig.step(3);
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  EXPECT_EQ(aligned, 1.0) << "engaged once the master is there";
  EXPECT_EQ(rig.master.moves, 1) << "aligned at that engagement: no move";
  EXPECT_GT(rig.master.commands, wrenches) << "engaged: the master's (zero) wrench again";
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "no step at engagement";
  EXPECT_LT(angle_between(rig.slave.goal.orientation, rig.slave.orientation), 1e-9);
  // Stopped on the way (the operator held the handle): the next engagement sends it again.
  rig.master.press_clutch(true);
  rig.step(2);
  rig.master.orientation = about_z(30);
  rig.master.press_clutch(false);
  rig.step(3);
  EXPECT_EQ(rig.master.moves, 2);
  EXPECT_EQ(rig.teleop.refused_sends(), 0u);

  s.align_master = false;
  Rig by_hand = rig_with(s);
  by_hand.step(5);
  EXPECT_EQ(by_hand.master.moves, 0) << "align_master false: the operator turns it";
}

// A master without move_cp (the Falcon, a read-only import): the optional output is not sent and
// not counted as refused; the operator is told how far off it is.
TEST(SurgicalLaw, AMasterWithoutMoveCpIsLeftToTheOperatorAndNothingCountsAsRefused) {
  saw::testing::FakeDevice master{"master", false}, slave{"slave"};
  saw::teleop::Teleoperation teleop("teleop", saw::TaskConfig::periodic(std::chrono::milliseconds(1), 0),
                                    follows_pose(),
                                    saw::teleop::law_spec<SurgicalLaw>(SurgicalLaw::Settings{}));
  saw::Manager manager;
  for (saw::Component* c : std::initializer_list<saw::Component*>{&master, &slave, &teleop}) manager.add(*c);
  manager.connect("teleop", "master", "master", "arm");
  manager.connect("teleop", "slave", "slave", "arm");
  manager.start_stepped();
  saw::testing::Stepper stepper{manager};
  master.orientation = about_z(40);
  for (int i = 0; i < 3; ++i) stepper({&master, &slave});
  const int wrenches = master.commands;
  for (int i = 0; i < 5; ++i) stepper({&master, &slave});
  EXPECT_GT(slave.goals, 0) << "held";
  EXPECT_EQ(teleop.refused_sends(), 0u) << "an optional output not offered is not a refusal";
  EXPECT_EQ(master.commands, wrenches + 5) << "its wrench goes on every cycle: no move is under way";
  manager.stop();
}

// Clutched, nothing is sent; the master turned past the tolerance meanwhile must come back before
// the law engages again; and no step at the release.
TEST(SurgicalLaw, AClutchDecouplesAndTheReleaseChecksTheOrientationAgain) {
  Rig rig = rig_with(SurgicalLaw::Settings{});
  rig.step(3);
  rig.master.position[0] += 0.01;
  rig.step(20);
  rig.slave.position = rig.slave.goal.position;  // the slave got there
  rig.master.press_clutch(true);
  rig.step(1);
  const int before = rig.slave.goals;
  rig.master.position = {0.2, 0.1, 0};
  rig.master.orientation = about_z(45);
  rig.step(3);
  EXPECT_EQ(rig.slave.goals, before) << "nothing while clutched";
  rig.master.press_clutch(false);
  rig.step(3);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "held: the master is 45 degrees off";
  double aligned = 1;
  ASSERT_EQ(rig.op.aligned(aligned), saw::Status::ok);
  EXPECT_EQ(aligned, 0.0);
  rig.master.orientation = about_z(2);
  rig.step(2);
  rig.master.position[1] += 0.01;
  rig.step(20);
  EXPECT_NEAR(rig.slave.goal.position[1], rig.slave.position[1] + 0.002, 1e-12)
      << "re-engaged from where the master was when it aligned";
}

// With needs_operator (the dVRK's head sensor): nothing is driven until the operator is present,
// nothing while away, and each return engages afresh — no step in the commanded pose.
TEST(SurgicalLaw, TheOperatorsPresenceGatesTeleoperationWithoutAStep) {
  saw::teleop::TeleopConfig c = follows_pose();
  c.needs_operator = true;
  Rig rig(c, saw::teleop::law_spec<SurgicalLaw>(SurgicalLaw::Settings{}));
  rig.step(3);
  rig.master.position[0] += 0.01;
  rig.step(10);
  EXPECT_EQ(rig.slave.goals, 0) << "no operator yet: nothing driven";
  rig.master.press_operator_present(true);
  rig.step(3);
  EXPECT_GT(rig.slave.goals, 0);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "engaged where the slave is";
  rig.master.position[0] += 0.01;
  rig.step(20);
  EXPECT_NEAR(rig.slave.goal.position[0], rig.slave.position[0] + 0.002, 1e-12) << "then follows, scaled";
  rig.slave.position = rig.slave.goal.position;
  rig.master.press_operator_present(false);
  rig.step(1);
  const int before = rig.slave.goals;
  rig.master.position[0] += 0.05;  // the hand moves away meanwhile
  rig.step(5);
  EXPECT_EQ(rig.slave.goals, before) << "the operator away: nothing";
  rig.master.press_operator_present(true);
  rig.step(3);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "back: no step";
}

// A master stream in bursts (a sample held for 10 ms, then a jump): the goal moves toward it no
// faster than the law's speeds, which the slave's own step checks (a little faster) all take.
TEST(SurgicalLaw, TheGoalMovesNoFasterThanItsSpeedsWhenTheMasterJumps) {
  SurgicalLaw::Settings s;
  s.max_linear_speed = 0.1;   // 0.1 mm a cycle
  s.max_angular_speed = 1.0;  // 1 mrad a cycle
  Rig rig = rig_with(s);
  rig.step(3);
  const saw::Pose start = rig.slave.goal;
  rig.master.position[0] += 0.01;       // 2 mm of goal at once
  rig.master.orientation = about_z(5);  // and 87 mrad
  saw::Pose last = start;
  double largest = 0, largest_turn = 0;
  for (int k = 0; k < 120; ++k) {
    rig.step(1);
    largest = std::max(largest, dist(rig.slave.goal.position, last.position));
    largest_turn = std::max(largest_turn, angle_between(rig.slave.goal.orientation, last.orientation) * deg);
    last = rig.slave.goal;
  }
  EXPECT_LE(largest, 0.0001 + 1e-12) << "no step beyond max_linear_speed in a period";
  EXPECT_LE(largest_turn, 0.001 + 1e-9) << "nor beyond max_angular_speed";
  EXPECT_NEAR(rig.slave.goal.position[0], start.position[0] + 0.002, 1e-12) << "and it gets there";
  EXPECT_NEAR(angle_between(rig.slave.goal.orientation, about_z(5)), 0, 1e-6);
}

// The slave's commands stopped (a stall: its watchdog tripped) while it lagged its goal: it holds
// where it is, so the goals resume from there, not from the last goal it never reached.
TEST(SurgicalLaw, AfterTheSlavesCommandsStoppedTheGoalsResumeFromWhereItHolds) {
  Rig rig = rig_with(SurgicalLaw::Settings{});
  rig.step(3);
  rig.master.position[0] += 0.01;
  rig.step(20);
  ASSERT_NEAR(rig.slave.goal.position[0], 0.002, 1e-12);
  rig.slave.position[0] = 0.001;  // 1 mm behind
  rig.slave.orientation = about_z(2);
  rig.slave.watchdog_trips = 1;
  rig.step(2);
  EXPECT_LT(dist(rig.slave.goal.position, rig.slave.position), 1e-12) << "engaged afresh where it holds";
  EXPECT_LT(angle_between(rig.slave.goal.orientation, rig.slave.orientation), 1e-9);
  rig.master.position[0] += 0.005;
  rig.step(20);
  EXPECT_NEAR(rig.slave.goal.position[0], 0.002, 1e-12) << "and follows the master from there";
}

TEST(SurgicalLaw, TheJawFollowsTheGripperWithinItsLimitsAndRate) {
  SurgicalLaw::Settings s;
  s.jaw_max = 0.8;
  s.jaw_rate = 2.0;  // 2 mrad a cycle
  Rig rig = rig_with(s);
  rig.slave.grip = 0.2;
  rig.master.grip = 1.0;  // beyond jaw_max
  rig.step(3);
  ASSERT_GT(rig.slave.jaw_goals, 0);
  EXPECT_NEAR(rig.slave.jaw_goal, 0.2 + 0.002 * rig.slave.jaw_goals, 1e-9) << "from the jaw, at the rate";
  rig.step(400);
  EXPECT_NEAR(rig.slave.jaw_goal, 0.8, 1e-12) << "and no further than jaw_max";
  Rig none = rig_with(s);  // a slave without a jaw gets no jaw goal
  none.master.grip = 0.5;
  none.step(5);
  EXPECT_EQ(none.slave.jaw_goals, 0);
}

TEST(SurgicalLaw, AThreeDofMasterDrivesTranslationAndHoldsOrientation) {
  SurgicalLaw::Settings s;
  s.orientation = false;
  Rig rig = rig_with(s);
  rig.slave.orientation = about_z(20);
  rig.master.orientation = about_z(-60);  // a Falcon's is nothing: not a misalignment
  rig.step(3);
  rig.master.orientation = about_z(80);
  rig.master.position[2] += 0.01;
  rig.step(20);
  EXPECT_NEAR(angle_between(rig.slave.goal.orientation, about_z(20)), 0, 1e-9);
  EXPECT_NEAR(rig.slave.goal.position[2], 0.002, 1e-12);
}

TEST(SurgicalLaw, AnInputThatIsNoRotationIsRefused) {
  Rig rig = rig_with(SurgicalLaw::Settings{});
  rig.step(3);
  rig.master.orientation = {0, 0, 0, 0.5};
  rig.step(2);
  EXPECT_GT(rig.teleop.rejected_inputs(), 0u);
}

}  // namespace
