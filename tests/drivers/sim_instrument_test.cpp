// The simulated instrument arm: its kinematics, and the device following poses and its jaw.
#include "saw/drivers/sim_instrument.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "saw/crtk_arm.hpp"
#include "saw/eigen.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;
using saw::drivers::InstrumentKinematics;
using saw::drivers::SimInstrument;
using saw::drivers::SimInstrumentConfig;
using Joints = InstrumentKinematics::Joints;

constexpr double wrist = InstrumentKinematics::wrist_pitch_to_yaw + InstrumentKinematics::wrist_yaw_to_tip;

TEST(InstrumentKinematics, ForwardByHand) {
  InstrumentKinematics k;
  const auto at = [&](Joints q) { return Eigen::Vector3d(k.fk(q).translation()); };
  EXPECT_TRUE(at(Joints::Zero()).isApprox(Eigen::Vector3d(0, 0, -wrist), 1e-12));
  EXPECT_TRUE(k.fk(Joints::Zero()).linear().isIdentity(1e-12)) << "every joint at zero: the base's frame";
  Joints q = Joints::Zero();
  q[2] = 0.1;
  EXPECT_TRUE(at(q).isApprox(Eigen::Vector3d(0, 0, -0.1 - wrist), 1e-12)) << "insertion along the shaft, −z";
  q[0] = M_PI / 2;  // the outer yaw turns the shaft about x through the remote centre
  EXPECT_TRUE(at(q).isApprox(Eigen::Vector3d(0, 0.1 + wrist, 0), 1e-12));
  q = Joints::Zero();
  q[4] = M_PI / 2;  // the wrist's pitch (about x) swings what is past it
  EXPECT_TRUE(at(q).isApprox(Eigen::Vector3d(0, wrist, 0), 1e-12));
  q[3] = M_PI / 2;  // the roll turns the wrist's axes with it
  EXPECT_NEAR(at(q).norm(), wrist, 1e-12);
  EXPECT_NEAR(at(q).z(), 0, 1e-12);
  EXPECT_NEAR(std::abs(at(q).x()), wrist, 1e-12);
}

TEST(InstrumentKinematics, JacobianMatchesFiniteDifferencesAndTheInverseUndoesTheForward) {
  InstrumentKinematics k;
  const SimInstrumentConfig c;
  for (const Joints& q : {(Joints() << 0.2, -0.1, 0.12, 0.5, 0.3, -0.4).finished(),
                          (Joints() << -0.6, 0.4, 0.05, -2.0, -0.9, 0.8).finished()}) {
    const Eigen::Matrix<double, 6, 6> j = k.jacobian(q);
    for (int i = 0; i < 6; ++i) {
      Joints dq = Joints::Zero();
      dq[i] = 1e-7;
      const Eigen::Isometry3d a = k.fk(q + dq), b = k.fk(q - dq);
      const Eigen::Vector3d linear = (a.translation() - b.translation()) / 2e-7;
      const Eigen::AngleAxisd turn(a.linear() * b.linear().transpose());
      EXPECT_LT((j.col(i).head<3>() - linear).norm(), 1e-6) << "joint " << i;
      EXPECT_LT((j.col(i).tail<3>() - turn.axis() * turn.angle() / 2e-7).norm(), 1e-6) << "joint " << i;
    }
    // From a seed 0.1 rad (and 1 cm) away in every joint.
    Joints back = q + Joints::Constant(0.1).cwiseProduct((Joints() << 1, 1, 0.1, 1, 1, 1).finished());
    ASSERT_TRUE(k.ik(k.fk(q), c.joint_min, c.joint_max, back));
    EXPECT_LT((back - q).norm(), 1e-4) << back.transpose();  // within 1 µm and 1e-5 rad at the tip
  }
  Joints q = c.initial_joints;
  Eigen::Isometry3d far = k.fk(q);
  far.translation().z() = -1.0;  // a metre down: past the insertion's stop
  EXPECT_FALSE(k.ik(far, c.joint_min, c.joint_max, q));
  EXPECT_NEAR(q[2], c.joint_max[2], 1e-12) << "the closest: the insertion at its stop";
}

class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(1ms, 0)) {
    namespace arm = saw::crtk::arm;
    auto& r = require("arm");
    saw::crtk::require(r, arm::measured_cp, measured_cp);
    saw::crtk::require(r, arm::servo_cp, servo_cp);
    saw::crtk::require(r, arm::jaw_measured_js, jaw);
    saw::crtk::require(r, arm::jaw_servo_jp, jaw_servo_jp);
    saw::crtk::require(r, arm::state_command, state_command);
  }
  saw::FunctionRead<saw::Pose> measured_cp;
  saw::FunctionWrite<saw::Pose> servo_cp;
  saw::FunctionRead<saw::JointState> jaw;
  saw::FunctionWrite<saw::JointState> jaw_servo_jp;
  saw::FunctionWrite<saw::StateCommand> state_command;
};

struct Rig {
  explicit Rig(SimInstrumentConfig c) : device("psm", saw::TaskConfig::periodic(1ms, 0), std::move(c)) {
    m.add(device);
    m.add(client);
    m.connect("client", "arm", "psm", "arm");
    m.start_stepped();
    m.step();
  }
  void steps(int n) { m.step_until(m.simulated_time() + saw::TimeNs{n} * 1'000'000); }
  saw::Pose pose() {
    saw::Pose p;
    EXPECT_EQ(client.measured_cp(p), saw::Status::ok);
    return p;
  }
  double jaw() {
    saw::JointState j;
    EXPECT_EQ(client.jaw(j), saw::Status::ok);
    return j.position[0];
  }
  SimInstrument device;
  Client client;
  saw::Manager m;
};

Eigen::Vector3d position(const saw::Pose& p) { return {p.position[0], p.position[1], p.position[2]}; }
Eigen::Quaterniond orientation(const saw::Pose& p) { return saw::to_eigen(p.orientation); }

saw::JointState jaw_goal(double angle) {
  saw::JointState j;
  j.size = 1;
  j.position[0] = angle;
  return j;
}

saw::Pose pose_of(const Eigen::Vector3d& x, const Eigen::Quaterniond& q) {
  return saw::Pose{saw::to_vec3(x), saw::to_quat(q)};
}

// A stream of goals — 1 cm along x and 20° about z over a second — is followed: within the
// joints' lag at every cycle, exactly once the stream stops; the jaw follows its goals within its
// limits, one beyond them refused; with the commands stopped it holds where it is.
TEST(SimInstrument, FollowsPosesAndItsJawAndHoldsWhenCommandsStop) {
  Rig rig(SimInstrumentConfig{});
  rig.steps(2);
  const saw::Pose start = rig.pose();
  ASSERT_NEAR(position(start).z(), -0.1 - wrist, 1e-9);
  double worst = 0, worst_turn = 0;
  Eigen::Vector3d x;
  Eigen::Quaterniond q;
  for (int k = 1; k <= 1000; ++k) {
    const double u = k / 1000.0;
    x = position(start) + Eigen::Vector3d(0.01 * u, 0, 0);
    q = Eigen::Quaterniond(Eigen::AngleAxisd(0.35 * u, Eigen::Vector3d::UnitZ()));
    ASSERT_EQ(rig.client.servo_cp(pose_of(x, q)), saw::Status::ok);
    ASSERT_EQ(rig.client.jaw_servo_jp(jaw_goal(0.8 * u)), saw::Status::ok);
    rig.steps(1);
    worst = std::max(worst, (position(rig.pose()) - x).norm());
    worst_turn = std::max(worst_turn, orientation(rig.pose()).angularDistance(q));
  }
  EXPECT_LT(worst, 1e-3) << "within a millimetre of the moving goal (10 mm/s through a 5 ms lag)";
  EXPECT_LT(worst_turn, 0.01) << "and 0.6 degrees of its turn (0.35 rad/s)";
  for (int k = 0; k < 50; ++k) {
    ASSERT_EQ(rig.client.servo_cp(pose_of(x, q)), saw::Status::ok);
    rig.steps(1);
  }
  EXPECT_LT((position(rig.pose()) - x).norm(), 1e-6) << "on the goal once it stops";
  EXPECT_LT(orientation(rig.pose()).angularDistance(q), 1e-5);
  EXPECT_NEAR(rig.jaw(), 0.8, 1e-3) << "the jaw on its goal";
  EXPECT_EQ(rig.device.summary().unreachable, 0u);

  ASSERT_EQ(rig.client.jaw_servo_jp(jaw_goal(2.0)), saw::Status::ok);
  rig.steps(50);
  EXPECT_EQ(rig.device.summary().jaw_refused, 1u) << "a jaw goal past jaw_max is refused";
  EXPECT_NEAR(rig.jaw(), 0.8, 1e-3);

  // Commands stop: the watchdog holds it where it is, however far the last goal was.
  const saw::Pose held = rig.pose();
  rig.steps(200);
  EXPECT_LT((position(rig.pose()) - position(held)).norm(), 1e-6);
  EXPECT_GE(rig.device.device_status().watchdog_trips, 1u);
}

// A goal the base refuses (outside the workspace, a jump faster than the speeds) never moves it.
TEST(SimInstrument, AGoalOutsideItsWorkspaceOrTooFarIsRefusedAndItHolds) {
  SimInstrumentConfig c;
  c.contract.workspace_min = {-0.05, -0.05, -0.2};
  c.contract.workspace_max = {0.05, 0.05, -0.05};
  Rig rig(c);
  rig.steps(2);
  const saw::Pose start = rig.pose();
  saw::Pose out = start;
  out.position[2] = -0.3;
  ASSERT_EQ(rig.client.servo_cp(out), saw::Status::ok);
  rig.steps(20);
  saw::Pose jump = start;
  jump.position[0] += 0.02;  // 2 cm in one cycle: 20 m/s
  ASSERT_EQ(rig.client.servo_cp(jump), saw::Status::ok);
  rig.steps(20);
  EXPECT_LT((position(rig.pose()) - position(start)).norm(), 1e-9);
  EXPECT_EQ(rig.device.device_status().refused.over_limit, 2u);
  EXPECT_EQ(rig.device.summary().poses, 0u);
}

}  // namespace
