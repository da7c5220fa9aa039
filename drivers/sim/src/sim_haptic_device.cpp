#include "saw/drivers/sim_haptic_device.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "saw/drivers/falcon/delta_dynamics.hpp"
#include "saw/drivers/falcon/delta_kinematics.hpp"
#include "saw/eigen.hpp"

namespace saw::drivers {
namespace {

// Fills the model's defaults where the configuration left zeros.
SimDeviceConfig with_defaults(SimDeviceConfig c) {
  const bool omni = c.model == ArmModel::omni;
  const falcon::DeltaArmDynamics delta;  // the Falcon's arms, as its simulated firmware has them
  if (c.inertia.isZero())
    c.inertia = omni ? Eigen::Vector3d(2e-4, 2e-4, 1e-4) : Eigen::Vector3d::Constant(delta.inertia);
  if (c.damping.isZero())
    c.damping = omni ? Eigen::Vector3d(2e-2, 2e-2, 1e-2) : Eigen::Vector3d::Constant(delta.damping);
  if (c.joint_min == c.joint_max) {
    c.joint_min = omni ? Eigen::Vector3d(-1.7, -1.2, -0.2) : Eigen::Vector3d::Constant(delta.angle_min);
    c.joint_max = omni ? Eigen::Vector3d(1.7, 1.75, 2.6) : Eigen::Vector3d::Constant(delta.angle_max);
  }
  if (c.contract.max_force <= 0) c.contract.max_force = omni ? 3.3 : 9.0;
  if (c.substeps < 1) c.substeps = 1;
  // The straight Omni arm is singular: by default start with the elbow bent. The Falcon starts
  // with its arms at 35°, where its measured_cp is zero.
  if (omni && c.initial_joints.isZero()) c.initial_joints = Eigen::Vector3d(0, 0, 1.2);
  if (!omni && c.initial_joints.isZero())
    c.initial_joints = Eigen::Vector3d::Constant(falcon::DeltaGeometry{}.angle_at_zero);
  if (c.wall.enabled) {
    if (!(c.wall.normal.norm() > 1e-9)) throw std::invalid_argument("the wall's normal must not be zero");
    c.wall.normal.normalize();
    if (c.wall.stiffness < 0 || c.wall.damping < 0)
      throw std::invalid_argument("the wall's stiffness and damping must not be negative");
  }
  if ((c.inertia.array() <= 0).any()) throw std::invalid_argument("inertia must be positive");
  if (!(c.hand.turn_axis.norm() > 1e-9)) throw std::invalid_argument("the hand's turn axis must not be zero");
  if (c.stylus && !omni) throw std::invalid_argument("a stylus is an Omni's (model omni)");
  if ((c.gimbal_min.array() >= c.gimbal_max.array()).any())
    throw std::invalid_argument("gimbal_min must be below gimbal_max");
  if ((c.joint_min.array() > c.joint_max.array()).any()) throw std::invalid_argument("joint_min > joint_max");
  return c;
}

constexpr std::string_view gimbal_names[3] = {"gimbal_pitch", "gimbal_roll", "gimbal_yaw"};

// The stylus's gimbal angles (about y, then x, then z) of a rotation R = Ry(a)·Rx(b)·Rz(c).
Eigen::Vector3d gimbal_angles(const Eigen::Matrix3d& r) noexcept {
  return {std::atan2(r(0, 2), r(2, 2)), std::asin(std::clamp(-r(1, 2), -1.0, 1.0)),
          std::atan2(r(1, 0), r(1, 1))};
}

Eigen::Matrix3d gimbal_rotation(const Eigen::Vector3d& g) noexcept {
  return (Eigen::AngleAxisd(g[0], Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(g[1], Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(g[2], Eigen::Vector3d::UnitZ()))
      .toRotationMatrix();
}

// The contract the base runs for it: a haptic device, safe at zero force.
DeviceConfig contract_of(const SimDeviceConfig& c) {
  DeviceConfig d;
  d.safe_state = SafeState::zero_force;
  d.settings() = c.contract;
  const ArmKinematics k(c.model);
  const auto names = k.joint_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    JointLimits j;
    j.name = std::string(names[i]);
    j.min = c.joint_min[static_cast<Eigen::Index>(i)];
    j.max = c.joint_max[static_cast<Eigen::Index>(i)];
    d.joints.push_back(j);
  }
  if (c.stylus)
    for (int i = 0; i < 3; ++i)
      d.joints.push_back(JointLimits{std::string(gimbal_names[i]), c.gimbal_min[i], c.gimbal_max[i]});
  return d;
}

}  // namespace

SimHapticDevice::SimHapticDevice(std::string name, TaskConfig task, SimDeviceConfig config)
    : SimHapticDevice(std::move(name), task, Checked<SimDeviceConfig>{with_defaults(std::move(config))}) {}

SimHapticDevice::SimHapticDevice(std::string name, TaskConfig task, Checked<SimDeviceConfig> config)
    : Device(std::move(name), task, contract_of(config.value)),
      config_(std::move(config.value)),
      kinematics_(config_.model) {
  q_ = config_.initial_joints.cwiseMax(config_.joint_min).cwiseMin(config_.joint_max);
  hand_origin_ = kinematics_.fk(q_);
  hand_target_ = hand_origin_;
  if (config_.stylus) {
    grip_.size = 1;
    (void)grip_.set_name(0, "gripper");
  }
  publish();

  auto& st = state_table();
  columns_.hand_force = st.add_column("hand_force", &hand_force_);
  columns_.servo_force = st.add_column("servo_force", &servo_force_);
  columns_.wall_force = st.add_column("wall_force", &wall_force_);
  columns_.servo_work = st.add_column("servo_work", &servo_work_);
  columns_.hand_work = st.add_column("hand_work", &hand_work_);
  columns_.wall_work = st.add_column("wall_work", &wall_work_);
  columns_.command_timeout = watchdog().holding_column();
  columns_.watchdog_trips = watchdog().trips_column();
  columns_.measured_cp = contract_columns().measured_cp;
  columns_.measured_cv = contract_columns().measured_cv;
  columns_.measured_js = contract_columns().measured_js;
  crtk_interface().add_command_read("servo_force", columns_.servo_force);
  // A force sensor at the tip: what the environment (the wall) pushes on it with.
  crtk::provide(crtk_interface(), crtk::arm::measured_cf, st, &contact_);
  if (config_.stylus) crtk::provide(crtk_interface(), crtk::arm::gripper_measured_js, st, &grip_);
  auto& sim = provide("sim");
  sim.add_command_write<ButtonCommand>("set_button",
                                       [this](const ButtonCommand& b) { set_button(b.button, b.pressed); });
  sim.add_command_read("hand_force", columns_.hand_force);
  sim.add_command_read("wall_force", columns_.wall_force);
  sim.add_command_read("servo_work", columns_.servo_work);
  sim.add_command_read("hand_work", columns_.hand_work);
  sim.add_command_read("wall_work", columns_.wall_work);
  sim.add_command_read("rejected_commands", st.add_column("rejected_commands", &rejected_column_));
}

void SimHapticDevice::set_button(std::uint8_t id, bool pressed) noexcept {
  if (id == 0) button(Button::clutch, pressed);
  if (id == 1) button(Button::operator_present, pressed);
}

void SimHapticDevice::enter_safe_state(SafeReason) {
  ++safe_entries_;
  applied_.setZero();  // the motors let go at once
}

Outcome SimHapticDevice::read() {
  if (t0_ < 0) t0_ = now();
  const double t = static_cast<double>(now() - t0_) * 1e-9;
  const HandSample h = hand_ = config_.hand.target(t, hand_cursor_);
  if (h.clutch != hand_clutch_) {  // a csv row's clutch column, or a scripted window
    hand_clutch_ = h.clutch;
    button(Button::clutch, h.clutch);
  }
  hand_target_ = hand_origin_ + h.position;
  return Outcome::done();
}

Outcome SimHapticDevice::write(const Setpoint& s) {
  applied_ = s.mode == ServoMode::cf
                 ? Eigen::Vector3d(s.wrench.force[0], s.wrench.force[1], s.wrench.force[2])
                 : Eigen::Vector3d::Zero();
  const double dt = static_cast<double>(config().period.count()) * 1e-9 / config_.substeps;
  integrate(dt, applied_, hand_target_);
  publish();
  return Outcome::done();
}

void SimHapticDevice::integrate(double dt, const Eigen::Vector3d& servo,
                                const Eigen::Vector3d& hand_target) noexcept {
  Eigen::Vector3d hand = Eigen::Vector3d::Zero(), contact = Eigen::Vector3d::Zero();
  Eigen::Vector3d x = kinematics_.fk(q_);
  for (int i = 0; i < config_.substeps; ++i) {
    const Eigen::Matrix3d j = kinematics_.jacobian(q_);
    const Eigen::Vector3d xd = j * qd_;
    hand = config_.hand.kind == HandScript::Kind::none
               ? Eigen::Vector3d::Zero()
               : Eigen::Vector3d(config_.hand.stiffness * (hand_target - x) - config_.hand.damping * xd);
    contact = wall(x, xd);
    const Eigen::Vector3d tau = j.transpose() * (servo + hand + contact);  // τ = Jᵀ·f
    const Eigen::Vector3d qdd = (tau - config_.damping.cwiseProduct(qd_)).cwiseQuotient(config_.inertia);
    qd_ += dt * qdd;  // semi-implicit Euler
    q_ += dt * qd_;
    for (int k = 0; k < 3; ++k) {  // hard stops
      if (q_[k] < config_.joint_min[k]) q_[k] = config_.joint_min[k], qd_[k] = std::max(0.0, qd_[k]);
      if (q_[k] > config_.joint_max[k]) q_[k] = config_.joint_max[k], qd_[k] = std::min(0.0, qd_[k]);
    }
    // Each force as it acted over this substep, along the path the tip took.
    const Eigen::Vector3d next = kinematics_.fk(q_), dx = next - x;
    servo_work_ += servo.dot(dx);
    hand_work_ += hand.dot(dx);
    wall_work_ += contact.dot(dx);
    x = next;
  }
  hand_force_ = to_vec3(hand);
  servo_force_ = to_vec3(servo);
  wall_force_ = to_vec3(contact);
  contact_.force = wall_force_;
}

Eigen::Vector3d SimHapticDevice::wall(const Eigen::Vector3d& x, const Eigen::Vector3d& xd) const noexcept {
  const VirtualWall& w = config_.wall;
  if (!w.enabled) return Eigen::Vector3d::Zero();
  const double depth = -(x - (hand_origin_ + w.point)).dot(w.normal);
  if (depth <= 0) return Eigen::Vector3d::Zero();
  const double push = w.stiffness * depth - w.damping * xd.dot(w.normal);
  return std::max(push, 0.0) * w.normal;  // a wall pushes, it never pulls the tip back in
}

void SimHapticDevice::publish() noexcept {
  Measured& m = measured();
  const Eigen::Vector3d x = kinematics_.fk(q_);
  const Eigen::Vector3d xd = kinematics_.jacobian(q_) * qd_;
  m.cp.position = to_vec3(x);
  m.cv.linear = to_vec3(xd);
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    m.js.position[i] = q_[k];
    m.js.velocity[i] = qd_[k];
  }
  if (config_.stylus) publish_stylus(static_cast<double>(config().period.count()) * 1e-9);
  rejected_column_ = device_status().refused.total();
}

// The hand holds the stylus at its turn: the gimbal takes what the arm's tip does not, within
// its limits; what is past them the stylus cannot follow.
void SimHapticDevice::publish_stylus(double dt) noexcept {
  Measured& m = measured();
  const Eigen::Matrix3d tip = (Eigen::AngleAxisd(q_[0], Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(q_[1] + q_[2], Eigen::Vector3d::UnitY()))
                                  .toRotationMatrix();  // the Omni chain's (arm_kinematics.cpp)
  const Eigen::Matrix3d hand =
      Eigen::AngleAxisd(hand_.turn, config_.hand.turn_axis.normalized()).toRotationMatrix();
  gimbal_ = gimbal_angles(tip.transpose() * hand).cwiseMax(config_.gimbal_min).cwiseMin(config_.gimbal_max);
  const Eigen::Quaterniond now(tip * gimbal_rotation(gimbal_));
  m.cv.angular = to_vec3(angular_velocity(stylus_, now, dt));  // the turn since the last cycle
  stylus_ = now;
  m.cp.orientation = to_quat(now);
  for (int k = 0; k < 3; ++k) m.js.position[static_cast<std::size_t>(3 + k)] = gimbal_[k];
  grip_.position[0] = hand_.grip;
}

}  // namespace saw::drivers
