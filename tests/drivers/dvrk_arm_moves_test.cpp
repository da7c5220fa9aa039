// DvrkArm's moves (move_cp, move_jp: the dVRK plans the trajectory), an MTM's free, and its joint
// space (measured_js, servo_jp) and measured_cf, against the scripted import on the stepped clock.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dvrk_test_rig.hpp"

namespace saw::drivers::dvrk {
namespace {

using testing::Rig;

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

DvrkArmConfig psm_in_a_box() {
  DvrkArmConfig c = testing::psm();
  c.contract.workspace_min = {-0.1, -0.1, -0.2};
  c.contract.workspace_max = {0.1, 0.1, 0.0};
  return c;
}

// Six joints as the simulated arm names them, each within ±1.
DvrkArmConfig with_joints(DvrkArmConfig c, bool servo_jp) {
  for (const char* n : {"x", "y", "z", "rx", "ry", "rz"}) c.joints.push_back(JointLimits{n, -1, 1, 0.5});
  c.servo_jp = servo_jp;
  return c;
}

Pose at(double x, double y, double z) {
  Pose p;
  p.position = {x, y, z};
  return p;
}

JointState joints(std::initializer_list<double> q) {
  JointState j;
  for (double v : q) j.position[j.size++] = v;
  return j;
}

void enable(Rig& r) {
  r.state_command(StateCommand::enable);
  r.step(40);
  ASSERT_TRUE(r.arm.following());
}

TEST(DvrkArmMoves, AMoveIsCheckedAndSentOnlyWhileTheArmIsDriven) {
  Rig r(psm_in_a_box());
  r.import.pose = at(0, 0, -0.1);
  r.step(2);
  r.command("move_cp", at(0.01, 0, -0.1));
  r.step(2);
  EXPECT_EQ(r.import.count("move_cp"), 0) << "not before ENABLED and homed";
  EXPECT_EQ(r.arm.summary().moves_refused, 1u);
  enable(r);
  Pose bad_quaternion = at(0, 0, -0.1);
  bad_quaternion.orientation = {0, 0, 0, 2};
  for (const Pose& p : {at(nan, 0, -0.1), at(0.5, 0, -0.1), at(0, 0, 0.05), bad_quaternion}) {
    r.command("move_cp", p);
    r.step();
  }
  EXPECT_EQ(r.import.count("move_cp"), 0) << "NaN, outside the workspace twice, not a rotation";
  EXPECT_EQ(r.arm.summary().moves_refused, 5u);
  r.command("move_cp", at(0.05, 0.02, -0.15));
  r.step();
  ASSERT_EQ(r.import.count("move_cp"), 1);
  EXPECT_EQ(r.import.received.back().pose.position[0], 0.05);
  EXPECT_TRUE(r.import.received.back().arm.is_homed);
  EXPECT_EQ(r.arm.summary().moves, 1u);
  r.step(5);
  EXPECT_EQ(r.import.count("move_cp"), 1) << "once";
  EXPECT_EQ(r.import.count("hold"), 0) << "a move goes on without servo commands: no safe command cuts it";
}

// While the dVRK runs the trajectory (busy), servo commands are held back; a stop during it sends
// the safe command, which ends the move.
TEST(DvrkArmMoves, ServoIsHeldBackDuringAMoveAndAStopEndsIt) {
  for (const bool stop_by_fault : {false, true}) {
    Rig r(psm_in_a_box());
    r.import.pose = at(0, 0, -0.1);
    enable(r);
    r.command("move_cp", at(0.05, 0, -0.1));
    r.step();
    r.import.state.is_busy = true;  // the dVRK's trajectory
    r.step();
    EXPECT_TRUE(r.arm.operating_state().is_busy) << "busy with the client's move: a client waits";
    const auto held = r.arm.summary().held_busy;
    r.servo_cp(at(0, 0, -0.1));
    r.step();
    EXPECT_EQ(r.import.count("servo_cp"), 0);
    EXPECT_EQ(r.arm.summary().held_busy, held + 1);
    if (stop_by_fault)
      r.import.state.state = OperatingStateValue::fault;
    else
      r.state_command(StateCommand::disable);
    r.step(3);
    EXPECT_EQ(r.import.count("hold"), 1) << (stop_by_fault ? "fault" : "disable") << ": the move is stopped";
    EXPECT_EQ(r.import.received.back().what, "hold");
  }
}

// The move is over once the arm is idle after its trajectory (or never showed one): a later busy
// (a homing from the console) is not the client's move, and a stop has nothing of ours to undo.
TEST(DvrkArmMoves, AMoveEndsWhenTheArmIsIdleAfterIt) {
  for (const bool seen_busy : {true, false}) {
    Rig r(psm_in_a_box());
    r.import.pose = at(0, 0, -0.1);
    enable(r);
    r.command("move_cp", at(0.05, 0, -0.1));
    r.step();
    ASSERT_EQ(r.import.count("move_cp"), 1);
    if (seen_busy) {
      r.import.state.is_busy = true;  // the dVRK's trajectory
      r.step(3);
      ASSERT_TRUE(r.arm.operating_state().is_busy);
      r.import.state.is_busy = false;
      r.step();
    } else {
      r.step(600);  // never shown busy: over after the window
    }
    EXPECT_FALSE(r.arm.operating_state().is_busy);
    r.import.state.is_busy = true;  // the console homes the arm
    r.step(3);
    EXPECT_FALSE(r.arm.operating_state().is_busy)
        << "not the client's move" << (seen_busy ? "" : " (never seen)");
    r.state_command(StateCommand::disable);
    r.step(3);
    EXPECT_EQ(r.import.count("hold"), 0) << "nothing of ours under way: no safe command";
  }
}

TEST(DvrkArmMoves, AMoveGivenWhileServoCommandsRunIsRefused) {
  Rig r(testing::mtm());
  testing::enable_mtm(r);
  r.command("move_cp", at(0, 0, 0));
  r.servo_cf({0.5, 0, 0});
  r.step();
  EXPECT_EQ(r.import.count("move_cp"), 0);
  EXPECT_EQ(r.arm.summary().moves_refused, 1u);
  r.step(5);  // commands stopped: the zero wrench, and no late move
  EXPECT_EQ(r.import.count("move_cp"), 0);
  EXPECT_EQ(r.import.received.back().what, "servo_cf");
}

// A client that streamed servo commands stops and moves the arm (the surgical law aligning an
// MTM): the move goes in the next cycle, without a hold before it (another topic: it could reach
// the arm after the move and cut it), and the silence after it trips no watchdog; the next servo
// command is sent again (it pre-empts what is left of the move at the dVRK).
TEST(DvrkArmMoves, AMoveEndsTheServoCommandsBeforeItWithoutATripOrAHold) {
  Rig r(testing::mtm());
  testing::enable_mtm(r);
  for (int i = 0; i < 3; ++i) {
    r.servo_cf({0, 0, 0});
    r.step();
  }
  const auto servo = r.import.count("servo_cf");
  r.command("move_cp", at(0, 0, 0));
  r.step();
  ASSERT_EQ(r.import.count("move_cp"), 1);
  EXPECT_EQ(r.import.count("servo_cf"), servo) << "the last wrench is not sent again";
  r.step(20);
  EXPECT_EQ(r.import.count("hold"), 0) << "nothing cuts the move";
  EXPECT_EQ(r.arm.watchdog_trips(), 0u) << "the stream's end after a move is no trip";
  EXPECT_FALSE(r.arm.operating_state().is_busy);
  r.import.state.is_busy = true;  // the dVRK's trajectory
  r.step();
  EXPECT_TRUE(r.arm.operating_state().is_busy) << "the move under way: the client waits";
  r.import.state.is_busy = false;
  r.step();
  EXPECT_FALSE(r.arm.operating_state().is_busy) << "there";
  r.servo_cf({0, 0, 0});
  r.step();
  EXPECT_EQ(r.import.count("servo_cf"), servo + 1);
}

TEST(DvrkArmMoves, JointGoalsAreTheDeclaredJointsWithinTheirLimits) {
  Rig r(with_joints(psm_in_a_box(), /*servo_jp=*/true));
  r.import.pose = at(0, 0, -0.1);
  r.import.js = joints({0.1, 0.2, 0.3, 0, 0, 0});
  enable(r);
  for (const JointState& j :
       {joints({0.1, 0.2}), joints({0, 0, 0, 0, 0, 1.5}), joints({0, 0, nan, 0, 0, 0})}) {
    r.command("move_jp", j);
    r.step();
  }
  EXPECT_EQ(r.import.count("move_jp"), 0) << "two joints of six, one over its limit, NaN";
  EXPECT_EQ(r.arm.summary().moves_refused, 3u);
  r.command("move_jp", joints({0.5, 0, 0, 0, 0, -0.5}));
  r.step();
  ASSERT_EQ(r.import.count("move_jp"), 1);
  EXPECT_EQ(r.import.received.back().joints.size, 6u);
  EXPECT_EQ(r.import.received.back().joints.position[5], -0.5);
  // servo_jp through the base's checks (size, limits, the step by max_velocity), then to the arm.
  r.command("servo_jp", joints({0.1, 0.2, 0.3, 0, 0, 0.0001}));
  r.step();
  r.command("servo_jp", joints({0.9, 0.2, 0.3, 0, 0, 0.0001}));  // 0.8 rad in 1 ms
  r.step();
  EXPECT_EQ(r.import.count("servo_jp"), 1);
  const auto& last = r.import.received[r.import.received.size() - 2];
  EXPECT_EQ(last.what, "servo_jp");
  EXPECT_EQ(last.joints.position[5], 0.0001);
  EXPECT_EQ(r.import.received.back().what, "hold") << "a refused command: the safe command";
}

TEST(DvrkArmMoves, MeasuredJointsAndWrenchArePassedOnChecked) {
  Rig r(with_joints(testing::mtm(), /*servo_jp=*/false));
  r.import.js = joints({0.1, 0.2, 0.3, 0.4, 0.5, 0.6});
  r.import.cf.force = {1, 2, 3};
  r.step(2);
  JointState js;
  ASSERT_EQ(r.arm.provided("arm")->find_command("measured_js")->read(nullptr, &js), Status::ok);
  EXPECT_EQ(js.size, 6u);
  EXPECT_EQ(js.position[5], 0.6);
  EXPECT_EQ(std::string_view(js.name[3].data()), "rx");
  Wrench cf;
  ASSERT_EQ(r.arm.provided("arm")->find_command("measured_cf")->read(nullptr, &cf), Status::ok);
  EXPECT_EQ(cf.force[2], 3.0);
  r.import.js = joints({9, 9, 9});  // another arm's, or a broken sample
  r.import.cf.force = {nan, 0, 0};
  r.step(2);
  ASSERT_EQ(r.arm.provided("arm")->find_command("measured_js")->read(nullptr, &js), Status::ok);
  EXPECT_EQ(js.position[0], 0.1) << "the last good sample stands";
  EXPECT_EQ(r.arm.summary().bad_joint_states, 2u);
  ASSERT_EQ(r.arm.provided("arm")->find_command("measured_cf")->read(nullptr, &cf), Status::ok);
  EXPECT_EQ(cf.force[2], 3.0);
}

// free: no effort (the MTM floats under the dVRK's gravity compensation): once driven, and it
// leaves nothing of ours to undo.
TEST(DvrkArmMoves, AnMtmIsFreedOnlyWhileDriven) {
  Rig r(testing::mtm());
  r.command("free");
  r.step(2);
  EXPECT_EQ(r.import.count("free"), 0);
  testing::enable_mtm(r);
  r.step(5);
  ASSERT_EQ(r.import.received.back().what, "servo_cf") << "the zero wrench after the last servo_cf";
  r.command("free");
  r.step();
  EXPECT_EQ(r.import.count("free"), 1);
  const int zero_wrenches = r.import.count("servo_cf");
  r.state_command(StateCommand::disable);
  r.step(3);
  EXPECT_EQ(r.import.count("servo_cf"), zero_wrenches) << "free left nothing to undo";
  EXPECT_EQ(r.arm.provided("arm")->find_command("free") != nullptr, true);
  Rig p(testing::psm());
  EXPECT_EQ(p.arm.provided("arm")->find_command("free"), nullptr) << "a PSM is never freed by us";
}

}  // namespace
}  // namespace saw::drivers::dvrk
