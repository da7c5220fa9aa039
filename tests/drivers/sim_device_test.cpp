// The simulated haptic devices: kinematics, dynamics, command validation, buttons, the hand.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <utility>

#include "saw/crtk_arm.hpp"
#include "saw/drivers/sim_haptic_device.hpp"
#include "saw/eigen.hpp"
#include "saw/manager.hpp"

namespace {

using namespace std::chrono_literals;
using saw::drivers::ArmKinematics;
using saw::drivers::ArmModel;
using saw::drivers::SimDeviceConfig;
using saw::drivers::SimHapticDevice;

constexpr double link = 0.133;

TEST(ArmKinematics, OmniForwardKinematicsByHand) {
  ArmKinematics k(ArmModel::omni);
  EXPECT_TRUE(k.fk({0, 0, 0}).isApprox(Eigen::Vector3d(2 * link, 0, 0)));
  // Elbow at +90° about y: the forearm points along −z.
  EXPECT_TRUE(k.fk({0, 0, M_PI / 2}).isApprox(Eigen::Vector3d(link, 0, -link), 1e-12));
  // Base yaw 90°: the straight arm points along +y.
  EXPECT_TRUE(k.fk({M_PI / 2, 0, 0}).isApprox(Eigen::Vector3d(0, 2 * link, 0), 1e-12));
}

TEST(ArmKinematics, JacobianMatchesFiniteDifferences) {
  for (auto [model, q] : {std::pair{ArmModel::omni, Eigen::Vector3d(0.3, -0.2, 0.9)},
                          std::pair{ArmModel::falcon, Eigen::Vector3d(0.4, 0.9, 0.6)}}) {
    ArmKinematics k(model);
    const Eigen::Matrix3d j = k.jacobian(q);
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d dq = Eigen::Vector3d::Zero();
      dq[c] = 1e-7;
      const Eigen::Vector3d column = (k.fk(q + dq) - k.fk(q - dq)) / 2e-7;
      EXPECT_TRUE(j.col(c).isApprox(column, 1e-6)) << "column " << c;
    }
  }
}

// The Falcon model is the real delta, in the `falcon` component's frame: zero with the arms at
// 35°, the grip further along +z as the arms go down, and ik() undoing fk() over the stops' range.
TEST(ArmKinematics, FalconIsTheDeltaAndItsInverseUndoesItsForward) {
  ArmKinematics k(ArmModel::falcon);
  constexpr double at_zero = 0.6108652381980153;  // 35°
  EXPECT_LT(k.fk(Eigen::Vector3d::Constant(at_zero)).norm(), 1e-12);
  const Eigen::Vector3d down = k.fk(Eigen::Vector3d::Constant(0.9));
  EXPECT_GT(down.z(), 0.01) << "all arms down: the grip moves along the axis, away from the motors";
  EXPECT_LT(std::hypot(down.x(), down.y()), 1e-12) << "and stays on the axis";
  EXPECT_GT(k.fk({0.9, at_zero, at_zero}).head<2>().norm(), 0.005) << "one arm alone moves it sideways";
  int checked = 0;
  for (double a = 0.25; a <= 1.05; a += 0.2)
    for (double b = 0.25; b <= 1.05; b += 0.2)
      for (double c = 0.25; c <= 1.05; c += 0.2) {
        const Eigen::Vector3d q(a, b, c);
        const Eigen::Vector3d x = k.fk(q);
        Eigen::Vector3d back;
        ASSERT_TRUE(k.ik(x, back)) << q.transpose();
        EXPECT_LT((back - q).norm(), 1e-9) << q.transpose();
        ++checked;
      }
  EXPECT_EQ(checked, 125);
  Eigen::Vector3d q;
  EXPECT_FALSE(k.ik({0, 0, 0.5}, q)) << "half a metre away is out of reach";
}

TEST(ArmKinematics, OmniInverseUndoesItsForward) {
  ArmKinematics k(ArmModel::omni);
  for (const Eigen::Vector3d& q :
       {Eigen::Vector3d(0, 0, 1.2), Eigen::Vector3d(0.4, -0.3, 0.8), Eigen::Vector3d(-1.1, 0.5, 2.0)}) {
    Eigen::Vector3d back;
    ASSERT_TRUE(k.ik(k.fk(q), back));
    EXPECT_LT((back - q).norm(), 1e-9) << q.transpose();
  }
}

// A client task that commands forces and watches events.
class Client : public saw::Task {
 public:
  Client() : Task("client", saw::TaskConfig::periodic(1ms, 0)) {
    namespace arm = saw::crtk::arm;
    auto& r = require("arm");
    saw::crtk::require(r, arm::measured_cp, measured_cp);
    saw::crtk::require(r, arm::measured_cv, measured_cv);
    saw::crtk::require(r, arm::measured_js, measured_js);
    saw::crtk::require(r, arm::gripper_measured_js, gripper, saw::Need::optional);
    saw::crtk::require(r, arm::servo_cf, servo_cf);
    saw::crtk::require(r, arm::state_command, state_command);
    saw::crtk::require(r, arm::clutch, [this](const saw::ButtonEvent& b) {
      clutch_events++;
      clutch = b.pressed;
    });
    saw::crtk::require(r, arm::operating_state_event,
                       [this](const saw::OperatingState& s) { last_state = s.state; });
    auto& s = require("sim");
    s.add_function("set_button", set_button);
    s.add_function("rejected_commands", rejected);
  }
  saw::FunctionRead<saw::Pose> measured_cp;
  saw::FunctionRead<saw::Twist> measured_cv;
  saw::FunctionRead<saw::JointState> measured_js;
  saw::FunctionRead<saw::JointState> gripper;
  saw::FunctionWrite<saw::Wrench> servo_cf;
  saw::FunctionWrite<saw::StateCommand> state_command;
  saw::FunctionWrite<saw::drivers::ButtonCommand> set_button;
  saw::FunctionRead<std::uint64_t> rejected;
  int clutch_events = 0;
  bool clutch = false;
  saw::OperatingStateValue last_state = saw::OperatingStateValue::disabled;
};

// These tests command a force once and watch the dynamics: the command watchdog (tested on its
// own below) is set out of their way unless a test sets it.
SimDeviceConfig patient(SimDeviceConfig c) {
  if (c.contract.command_timeout == 0) c.contract.command_timeout = 60'000'000'000;
  return c;
}

struct Rig {
  explicit Rig(SimDeviceConfig c) : device("dev", saw::TaskConfig::periodic(1ms, 0), patient(std::move(c))) {
    m.add(device);
    m.add(client);
    m.connect("client", "arm", "dev", "arm");
    m.connect("client", "sim", "dev", "sim");
    m.start_stepped();
    m.step();  // one row published
  }
  void steps(int n) { m.step_until(m.simulated_time() + saw::TimeNs{n} * 1'000'000); }
  Eigen::Vector3d position() {
    saw::Pose p;
    EXPECT_EQ(client.measured_cp(p), saw::Status::ok);
    return {p.position[0], p.position[1], p.position[2]};
  }
  SimHapticDevice device;
  Client client;
  saw::Manager m;
};

// A 6-DOF stylus: its orientation is the hand's turn (the gimbal takes what the arm's tip does
// not), read with its angular velocity and the gimbal's joints; the gripper is the hand's grip;
// a turn past the gimbal's limits is not followed.
TEST(SimHapticDevice, AStylusReadsTheHandsTurnAndGrip) {
  SimDeviceConfig c;
  c.stylus = true;
  c.hand.kind = saw::drivers::HandScript::Kind::sinusoid;
  c.hand.amplitude = Eigen::Vector3d(0.02, 0, 0);
  c.hand.frequency = 0.5;
  c.hand.turn_axis = Eigen::Vector3d(0, 0.6, 0.8);
  c.hand.turn_amplitude = 20 * M_PI / 180;
  c.hand.grip_mean = 0.5;
  c.hand.grip_amplitude = 0.2;
  Rig rig(c);
  double worst = 0, worst_rate = 0, worst_grip = 0, largest_turn = 0;
  for (int k = 0; k < 40; ++k) {
    rig.steps(50);
    const double t = static_cast<double>(rig.m.simulated_time()) * 1e-9;  // the row's hand
    const double wave = std::sin(2 * M_PI * 0.5 * t);
    saw::Pose p;
    saw::Twist v;
    saw::JointState js, grip;
    ASSERT_EQ(rig.client.measured_cp(p), saw::Status::ok);
    ASSERT_EQ(rig.client.measured_cv(v), saw::Status::ok);
    ASSERT_EQ(rig.client.measured_js(js), saw::Status::ok);
    ASSERT_EQ(rig.client.gripper(grip), saw::Status::ok);
    const Eigen::Quaterniond q = saw::to_eigen(p.orientation);
    const Eigen::Quaterniond hand(
        Eigen::AngleAxisd(c.hand.turn_amplitude * wave, c.hand.turn_axis.normalized()));
    worst = std::max(worst, q.angularDistance(hand));
    largest_turn = std::max(largest_turn, q.angularDistance(Eigen::Quaterniond::Identity()));
    const Eigen::Vector3d rate =
        c.hand.turn_axis.normalized() * c.hand.turn_amplitude * 2 * M_PI * 0.5 * std::cos(2 * M_PI * 0.5 * t);
    worst_rate =
        std::max(worst_rate, (Eigen::Vector3d(v.angular[0], v.angular[1], v.angular[2]) - rate).norm());
    worst_grip = std::max(worst_grip, std::abs(grip.position[0] - (0.5 + 0.2 * wave)));
    ASSERT_EQ(js.size, 6u);
    EXPECT_EQ(js.name_of(3), "gimbal_pitch");
    EXPECT_EQ(grip.size, 1u);
  }
  EXPECT_LT(worst, 1e-6) << "the stylus's orientation is the hand's";
  EXPECT_GT(largest_turn, 0.3) << "and it turned (close to 20 degrees)";
  EXPECT_LT(worst_rate, 0.01) << "its angular velocity the turn's (rad/s, one cycle's difference)";
  EXPECT_LT(worst_grip, 1e-9) << "the gripper the hand's grip";

  // A turn of 170 degrees about y (the tip pitched 69 degrees down: 101 degrees for the gimbal)
  // with the gimbal's pitch limited to 57 degrees: it stops there, the stylus short of the hand.
  SimDeviceConfig far = c;
  far.hand.turn_axis = Eigen::Vector3d::UnitY();
  far.hand.turn_amplitude = 170 * M_PI / 180;
  far.hand.phase = M_PI / 2;  // the whole turn at t = 0
  far.gimbal_max[0] = 1.0;
  Rig held(far);
  held.steps(2);
  saw::JointState js;
  ASSERT_EQ(held.client.measured_js(js), saw::Status::ok);
  EXPECT_NEAR(js.position[3], 1.0, 1e-12) << "gimbal_pitch at its limit";
  saw::Pose p;
  ASSERT_EQ(held.client.measured_cp(p), saw::Status::ok);
  const Eigen::Quaterniond q = saw::to_eigen(p.orientation);
  EXPECT_NEAR(q.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(far.hand.turn_amplitude, Eigen::Vector3d::UnitY()))),
              far.hand.turn_amplitude - (js.position[1] + js.position[2]) - 1.0, 1e-9)
      << "short of the hand by what the gimbal could not take";
}

TEST(SimHapticDevice, ForceMovesTheTipAlongItAndDampingStopsIt) {
  for (auto model : {ArmModel::omni, ArmModel::falcon}) {
    SimDeviceConfig c;
    c.model = model;
    Rig rig(c);
    rig.steps(2);
    const Eigen::Vector3d start = rig.position();
    const saw::Vec3 f{0.5, -0.3, 0.2};
    ASSERT_EQ(rig.client.servo_cf(saw::Wrench{f, {}}), saw::Status::ok);
    rig.steps(20);
    const Eigen::Vector3d moved = rig.position() - start;
    EXPECT_GT(moved.dot(Eigen::Vector3d(f[0], f[1], f[2])), 0) << "τ = Jᵀf pushes the tip along f";
    ASSERT_EQ(rig.client.servo_cf(saw::Wrench{}), saw::Status::ok);
    rig.steps(5000);
    saw::Twist v;
    ASSERT_EQ(rig.client.measured_cv(v), saw::Status::ok);
    EXPECT_LT(std::hypot(v.linear[0], v.linear[1], v.linear[2]), 1e-3)
        << "damping brings it to rest (model " << static_cast<int>(model) << ")";
  }
}

// The motors' work is the physics': with (almost) no damping, what they did is the arm's kinetic
// energy, ½·Σ I·q̇² from its joint velocities; and a motor that applies nothing does no work.
TEST(SimHapticDevice, TheMotorsWorkIsTheKineticEnergyTheyGaveTheArm) {
  for (auto model : {ArmModel::omni, ArmModel::falcon}) {
    SimDeviceConfig c;
    c.model = model;
    c.damping = Eigen::Vector3d::Constant(1e-9);  // (zero would mean the model's default)
    c.substeps = 10;
    Rig rig(c);
    rig.steps(5);
    EXPECT_EQ(rig.device.servo_work(), 0.0) << "no force, no work";
    ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{0.3, -0.2, 0.4}, {}}), saw::Status::ok);
    rig.steps(15);
    ASSERT_EQ(rig.client.servo_cf(saw::Wrench{}), saw::Status::ok);
    rig.steps(1);
    const double work = rig.device.servo_work();
    saw::JointState js;
    ASSERT_EQ(rig.client.measured_js(js), saw::Status::ok);
    const Eigen::Vector3d inertia = rig.device.device_config().inertia;
    double kinetic = 0;
    for (int k = 0; k < 3; ++k)
      kinetic += 0.5 * inertia[k] * js.velocity[static_cast<std::size_t>(k)] *
                 js.velocity[static_cast<std::size_t>(k)];
    ASSERT_GT(kinetic, 1e-5);
    EXPECT_NEAR(work, kinetic, 0.01 * kinetic) << "model " << static_cast<int>(model);
    rig.steps(10);
    EXPECT_EQ(rig.device.servo_work(), work) << "coasting: the motors do nothing";
    EXPECT_EQ(rig.device.hand_work(), 0.0);
    EXPECT_EQ(rig.device.wall_work(), 0.0);
  }
}

// sensor_msgs/JointState pairs positions with joints by name: measured_js names every joint.
TEST(SimHapticDevice, MeasuredJsNamesTheModelsJoints) {
  for (auto [model, names] : {std::pair{ArmModel::omni, std::array{"yaw", "shoulder_pitch", "elbow_pitch"}},
                              std::pair{ArmModel::falcon, std::array{"arm0", "arm1", "arm2"}}}) {
    SimDeviceConfig c;
    c.model = model;
    Rig rig(c);
    saw::JointState js;
    ASSERT_EQ(rig.client.measured_js(js), saw::Status::ok);
    ASSERT_EQ(js.size, 3u);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(js.name_of(i), names[i]);
    EXPECT_TRUE(saw::check_value(js)) << "a value another process accepts";
  }
}

// The arm interface is the one crtk_arm.hpp declares: every member the device serves has the
// declared kind and type, so a client written against the declaration connects.
TEST(SimHapticDevice, ProvidesTheDeclaredCrtkArm) {
  SimHapticDevice d("dev", saw::TaskConfig::periodic(1ms, 0), SimDeviceConfig{});
  const saw::ProvidedInterface* arm = d.provided(saw::crtk::arm::interface_name);
  ASSERT_NE(arm, nullptr);
  int served = 0;
  for (const auto& m : saw::crtk::arm::members) {
    const bool event = saw::is_event(m.signature.kind);
    const saw::Signature* found = nullptr;
    if (event) {
      if (const auto* e = arm->find_event(m.name)) found = &e->signature();
    } else if (const auto* c = arm->find_command(m.name)) {
      found = &c->signature;
    }
    if (m.name == saw::crtk::arm::servo_cp.name) {
      EXPECT_EQ(found, nullptr) << "the sim device does not serve servo_cp";
      continue;
    }
    ASSERT_NE(found, nullptr) << m.name;
    EXPECT_EQ(*found, m.signature) << m.name;
    ++served;
  }
  EXPECT_EQ(served, static_cast<int>(saw::crtk::arm::members.size()) - 1);
}

TEST(SimHapticDevice, JointLimitsHold) {
  SimDeviceConfig c;
  c.model = ArmModel::falcon;
  Rig rig(c);
  // Pushed along the axis, away from the motors: every arm goes down onto its stop.
  ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{0, 0, 5}, {}}), saw::Status::ok);
  rig.steps(3000);
  saw::JointState js;
  ASSERT_EQ(rig.client.measured_js(js), saw::Status::ok);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(js.position[i], 1.1, 1e-12) << i;
  ArmKinematics k(ArmModel::falcon);
  EXPECT_TRUE(rig.position().isApprox(k.fk(Eigen::Vector3d::Constant(1.1)), 1e-12));
}

// The delta's joint-space dynamics: a force at the grip accelerates it as its mass at the grip,
// M = J⁻ᵀ·I·J⁻¹ (0.09–0.16 kg at the centre), says; then damping stops it.
TEST(SimHapticDevice, FalconMovesUnderAForceAsItsMassAtTheGripSays) {
  SimDeviceConfig c;
  c.model = ArmModel::falcon;
  Rig rig(c);
  rig.steps(1);
  const Eigen::Vector3d start = rig.position();
  ArmKinematics k(ArmModel::falcon);
  const Eigen::Matrix3d j = k.jacobian(Eigen::Vector3d::Constant(0.6108652381980153));
  const Eigen::Matrix3d mass =
      j.transpose().inverse() * rig.device.device_config().inertia.asDiagonal() * j.inverse();
  for (const Eigen::Vector3d& f : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, -1)}) {
    const Eigen::Vector3d predicted = 0.5 * (mass.inverse() * f) * 0.01 * 0.01;  // ½·a·t², 10 ms
    Rig r(c);
    r.steps(1);
    const Eigen::Vector3d from = r.position();
    ASSERT_EQ(r.client.servo_cf(saw::Wrench{{f.x(), f.y(), f.z()}, {}}), saw::Status::ok);
    r.steps(10);
    const Eigen::Vector3d moved = r.position() - from;
    std::printf(
        "falcon: %.0f N along (%g, %g, %g) for 10 ms moves it %.2f mm (rigid-body estimate %.2f mm)\n",
        f.norm(), f.x(), f.y(), f.z(), moved.norm() * 1e3, predicted.norm() * 1e3);
    EXPECT_GT(moved.normalized().dot(f.normalized()), 0.95) << "along the force";
    EXPECT_NEAR(moved.norm(), predicted.norm(), 0.3 * predicted.norm());
  }
  EXPECT_TRUE(rig.position().isApprox(start, 1e-12)) << "no force, no motion";
}

TEST(SimHapticDevice, RejectsNonFiniteAndOversizedForcesBeforeTheDynamics) {
  SimDeviceConfig c;
  c.model = ArmModel::falcon;
  Rig rig(c);
  rig.steps(2);
  const Eigen::Vector3d start = rig.position();
  for (const saw::Vec3& f :
       {saw::Vec3{std::nan(""), 0, 0}, saw::Vec3{0, INFINITY, 0}, saw::Vec3{100, 0, 0}}) {
    ASSERT_EQ(rig.client.servo_cf(saw::Wrench{f, {}}), saw::Status::ok);  // queued...
    rig.steps(10);                                                        // ...and refused by the device
  }
  EXPECT_EQ(rig.device.rejected_commands(), 3u);
  std::uint64_t reported = 0;
  ASSERT_EQ(rig.client.rejected(reported), saw::Status::ok);
  EXPECT_EQ(reported, 3u);
  EXPECT_TRUE(rig.position().isApprox(start, 1e-12)) << "no rejected force moved the device";
  // A good command after a bad one is applied; a bad one after a good one stops it.
  ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{2, 0, 0}, {}}), saw::Status::ok);
  rig.steps(10);
  EXPECT_GT(rig.position().x(), start.x());
}

TEST(SimHapticDevice, StateCommandsAndDisabledDeviceIgnoresForces) {
  SimDeviceConfig c;
  c.model = ArmModel::falcon;
  c.contract.start_enabled = false;
  Rig rig(c);
  ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{2, 0, 0}, {}}), saw::Status::ok);
  rig.steps(20);
  EXPECT_NEAR(rig.position().x(), 0, 1e-12);
  ASSERT_EQ(rig.client.state_command(saw::StateCommand::enable), saw::Status::ok);
  rig.steps(20);
  EXPECT_EQ(rig.client.last_state, saw::OperatingStateValue::enabled);
  EXPECT_NEAR(rig.position().x(), 0, 1e-12) << "a command sent while disabled is not applied once enabled";
  ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{2, 0, 0}, {}}), saw::Status::ok);
  rig.steps(20);
  EXPECT_GT(rig.position().x(), 0);
  ASSERT_EQ(rig.client.state_command(saw::StateCommand::pause), saw::Status::ok);
  rig.steps(3);
  EXPECT_EQ(rig.client.last_state, saw::OperatingStateValue::paused);
}

TEST(SimHapticDevice, ButtonsEmitEvents) {
  Rig rig(SimDeviceConfig{});
  ASSERT_EQ(rig.client.set_button({0, true}), saw::Status::ok);
  rig.steps(3);
  EXPECT_TRUE(rig.client.clutch);
  ASSERT_EQ(rig.client.set_button({0, false}), saw::Status::ok);
  rig.steps(3);
  EXPECT_FALSE(rig.client.clutch);
  EXPECT_EQ(rig.client.clutch_events, 2);
}

TEST(SimHapticDevice, HandDrivesASinusoid) {
  SimDeviceConfig c;
  c.hand.kind = saw::drivers::HandScript::Kind::sinusoid;
  c.hand.amplitude = {0.02, 0, 0};
  c.hand.frequency = 0.5;
  c.hand.stiffness = 300;
  Rig rig(c);
  const Eigen::Vector3d origin = rig.position();
  double max_x = -1, min_x = 1;
  rig.steps(2000);  // settle
  for (int i = 0; i < 2000; ++i) {
    rig.steps(1);
    const double x = rig.position().x() - origin.x();
    max_x = std::max(max_x, x);
    min_x = std::min(min_x, x);
  }
  EXPECT_NEAR(max_x, 0.02, 0.004);
  EXPECT_NEAR(min_x, -0.02, 0.004);
}

TEST(SimHapticDevice, HandFollowsALineAndACsv) {
  SimDeviceConfig line;
  line.hand.kind = saw::drivers::HandScript::Kind::line;
  line.hand.to = {0, 0.03, 0};
  line.hand.duration = 1.0;
  line.hand.stiffness = 300;
  Rig a(line);
  const Eigen::Vector3d origin = a.position();
  a.steps(3000);
  EXPECT_TRUE((a.position() - origin).isApprox(Eigen::Vector3d(0, 0.03, 0), 0.05));

  const std::string path = ::testing::TempDir() + "hand.csv";
  {
    std::ofstream f(path);
    f << "t,x,y,z,clutch\n0,0,0,0,0\n0.5,0,0,0.02,1\n3,0,0,0.02,0\n";
  }
  SimDeviceConfig csv;
  csv.hand.kind = saw::drivers::HandScript::Kind::csv;
  csv.hand.samples = saw::drivers::HandScript::load_csv(path);
  csv.hand.stiffness = 300;
  Rig b(csv);
  const Eigen::Vector3d o = b.position();
  b.steps(1500);
  EXPECT_NEAR(b.position().z() - o.z(), 0.02, 0.003);
  EXPECT_TRUE(b.client.clutch) << "the CSV's clutch column pressed the button";
  EXPECT_THROW(saw::drivers::HandScript::load_csv(path + ".missing"), std::runtime_error);
}

// The human-like hand: minimum-jerk reaches (at rest at both ends, half-way at half time), a dwell
// at each target, back to the origin, and round again.
TEST(HandScript, ReachesAreMinimumJerkWithDwells) {
  saw::drivers::HandScript h;
  h.kind = saw::drivers::HandScript::Kind::reach;
  h.targets = {Eigen::Vector3d(0.02, 0, 0), Eigen::Vector3d(0.02, 0.01, 0)};
  h.reach_time = 0.8;
  h.dwell = 0.2;
  std::size_t cursor = 0;
  const auto at = [&](double t) { return h.target(t, cursor).position; };
  EXPECT_TRUE(at(0).isZero());
  EXPECT_TRUE(at(0.4).isApprox(Eigen::Vector3d(0.01, 0, 0)));  // symmetric profile: half-way at half time
  EXPECT_LT(at(0.1).x(), 0.1 * 0.02) << "slow start: 10u³−15u⁴+6u⁵ is 0.0156 at u=1/8, not 0.125";
  for (double t : {0.8, 0.9, 1.0})
    EXPECT_TRUE(at(t).isApprox(h.targets[0])) << "dwell at the target, t=" << t;
  EXPECT_TRUE(at(1.8).isApprox(h.targets[1]));
  EXPECT_NEAR(at(2.8).norm(), 0, 1e-12) << "back at the origin after the last target";
  EXPECT_TRUE(at(3.4).isApprox(at(0.4))) << "and round again";
  // Zero velocity at both ends of a reach (and nothing faster than the profile's 1.875·d/T peak).
  const double dt = 1e-4, peak = 1.875 * 0.02 / 0.8;
  EXPECT_NEAR((at(dt) - at(0)).norm() / dt, 0, 1e-3);
  EXPECT_NEAR((at(0.8) - at(0.8 - dt)).norm() / dt, 0, 1e-3);
  EXPECT_NEAR((at(0.4 + dt) - at(0.4)).norm() / dt, peak, 1e-3);
}

// Physiological tremor: sub-millimetre, in the 8–12 Hz band on every axis, on top of the motion.
TEST(HandScript, TremorIsSubMillimetreInItsBand) {
  saw::drivers::HandScript h;
  h.kind = saw::drivers::HandScript::Kind::line;  // holding still at the origin
  h.tremor_amplitude = 3e-4;
  h.tremor_frequency = 10;
  std::size_t cursor = 0;
  Eigen::Vector3d peak = Eigen::Vector3d::Zero();
  std::array<int, 3> crossings{};
  Eigen::Vector3d last = h.target(0, cursor).position;
  const int n = 100'000;  // 10 s at 10 kHz
  for (int i = 1; i <= n; ++i) {
    const Eigen::Vector3d p = h.target(i * 1e-4, cursor).position;
    peak = peak.cwiseMax(p.cwiseAbs());
    for (int k = 0; k < 3; ++k)
      if ((p[k] > 0) != (last[k] > 0)) ++crossings[static_cast<std::size_t>(k)];
    last = p;
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(peak[k], 3e-4 + 1e-12);
    EXPECT_GT(peak[k], 2.9e-4);
    const double hz = crossings[static_cast<std::size_t>(k)] / 2.0 / 10.0;
    EXPECT_GE(hz, 8.0) << "axis " << k;
    EXPECT_LE(hz, 12.0) << "axis " << k;
  }
  h.kind = saw::drivers::HandScript::Kind::none;  // no hand: no tremor either
  EXPECT_TRUE(h.target(0.0123, cursor).position.isZero());
}

// The contact scenario: the hand pushes the tip into a stiff wall. The wall pushes back along its
// normal by its stiffness times the depth, holds the hand's push at rest, and never pulls.
TEST(SimHapticDevice, AVirtualWallPushesBackByItsStiffness) {
  SimDeviceConfig c;
  c.hand.kind = saw::drivers::HandScript::Kind::line;
  c.hand.to = {0.02, 0, 0};  // 2 cm into the wall: the hand's spring pushes ~ 300 N/m · (2 cm − depth)
  c.hand.duration = 0.5;
  c.hand.stiffness = 300;
  c.wall.enabled = true;
  c.wall.point = {0.005, 0, 0};
  c.wall.normal = {-1, 0, 0};  // the wall's free side faces the origin
  c.wall.stiffness = 3000;
  Rig rig(c);
  const Eigen::Vector3d origin = rig.position();
  EXPECT_TRUE(rig.device.wall_force().isZero()) << "no contact yet";
  rig.steps(4000);
  const double x = rig.position().x() - origin.x();
  const double depth = x - 0.005;
  ASSERT_GT(depth, 0) << "the tip is in the wall";
  const Eigen::Vector3d f = rig.device.wall_force();
  EXPECT_NEAR(f.x(), -3000 * depth, 0.05) << "stiffness times depth, against the push";
  EXPECT_NEAR(f.y(), 0, 1e-9);
  EXPECT_NEAR(f.x() + 300 * (0.02 - x), 0, 0.1) << "at rest: the wall holds the hand's push";
  EXPECT_LT(depth, 0.003) << "a stiff wall: the hand's 300 N/m against 3000 N/m";
  // Outside the wall (a wall pulling the tip back in would make contact sticky).
  SimDeviceConfig away = c;
  away.hand.to = {-0.01, 0, 0};
  Rig free(away);
  free.steps(2000);
  EXPECT_TRUE(free.device.wall_force().isZero());
}

// A device never keeps pushing: without a fresh servo_cf for command_timeout, zero force, and
// the state says so; the next command applies again.
TEST(SimHapticDevice, CommandWatchdogDropsTheForceWhenCommandsStop) {
  SimDeviceConfig c;
  c.model = ArmModel::falcon;
  c.contract.command_timeout = 3'000'000;  // 3 periods
  Rig rig(c);
  const auto& st = rig.device.state_table();
  const auto& col = rig.device.columns();
  const auto applied = [&] {
    saw::Vec3 f{};
    EXPECT_EQ(st.read_latest(col.servo_force, f), saw::Status::ok);
    return f;
  };
  const auto timed_out = [&] {
    bool t = false;
    EXPECT_EQ(st.read_latest(col.command_timeout, t), saw::Status::ok);
    return t;
  };
  for (int round = 1; round <= 2; ++round) {
    for (int i = 0; i < 10; ++i) {  // a commander sending every period
      ASSERT_EQ(rig.client.servo_cf(saw::Wrench{{1, 0, 0}, {}}), saw::Status::ok);
      rig.steps(1);
      ASSERT_EQ(applied(), (saw::Vec3{1, 0, 0}));
      ASSERT_FALSE(timed_out());
    }
    rig.steps(3);  // the commander stops: 3 ms is the timeout, not beyond it
    EXPECT_EQ(applied(), (saw::Vec3{1, 0, 0})) << "round " << round;
    EXPECT_FALSE(timed_out());
    rig.steps(1);
    EXPECT_EQ(applied(), (saw::Vec3{0, 0, 0})) << "round " << round;
    EXPECT_TRUE(timed_out());
    EXPECT_EQ(rig.device.watchdog_trips(), static_cast<std::uint64_t>(round));
    rig.steps(50);
    EXPECT_EQ(applied(), (saw::Vec3{0, 0, 0})) << "it holds at zero";
    EXPECT_EQ(rig.device.watchdog_trips(), static_cast<std::uint64_t>(round)) << "one trip per stop";
  }
}

TEST(SimHapticDevice, CommandTimeoutDefaultsToThreePeriodsAndIsAtLeastOne) {
  SimHapticDevice d("d", saw::TaskConfig::periodic(2ms, 0), SimDeviceConfig{});
  EXPECT_EQ(d.command_timeout(), 6'000'000);
  SimDeviceConfig c;
  c.contract.command_timeout = 1'000'000;
  EXPECT_THROW(SimHapticDevice("e", saw::TaskConfig::periodic(2ms, 0), c), std::invalid_argument);
}

}  // namespace
