#include "saw/drivers/sim_instrument.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "saw/crtk_arm.hpp"
#include "saw/eigen.hpp"

namespace saw::drivers {
namespace {

SimInstrumentConfig checked(SimInstrumentConfig c) {
  if ((c.joint_min.array() >= c.joint_max.array()).any())
    throw std::invalid_argument("joint_min must be below joint_max");
  if ((c.max_velocity.array() <= 0).any()) throw std::invalid_argument("max_velocity must be positive");
  if (!(c.servo_lag >= 0)) throw std::invalid_argument("servo_lag must not be negative");
  if (!(c.jaw_min < c.jaw_max) || !(c.jaw_rate > 0))
    throw std::invalid_argument("jaw_min below jaw_max, jaw_rate positive");
  c.initial_joints = c.initial_joints.cwiseMax(c.joint_min).cwiseMin(c.joint_max);
  c.initial_jaw = std::clamp(c.initial_jaw, c.jaw_min, c.jaw_max);
  return c;
}

// The contract the base runs for it: an arm taking poses, safe where it holds.
DeviceConfig contract_of(const SimInstrumentConfig& c) {
  DeviceConfig d;
  d.settings() = c.contract;
  d.safe_state = SafeState::hold;
  d.servo_cf = false;
  d.servo_cp = true;
  const auto names = InstrumentKinematics::joint_names();
  for (int i = 0; i < InstrumentKinematics::dof; ++i)
    d.joints.push_back(JointLimits{std::string(names[static_cast<std::size_t>(i)]), c.joint_min[i],
                                   c.joint_max[i], c.max_velocity[i]});
  return d;
}

Eigen::Isometry3d isometry(const Pose& p) noexcept {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = to_eigen(p.orientation).normalized().toRotationMatrix();
  t.translation() = Eigen::Vector3d(p.position[0], p.position[1], p.position[2]);
  return t;
}

}  // namespace

SimInstrument::SimInstrument(std::string name, TaskConfig task, SimInstrumentConfig config)
    : SimInstrument(std::move(name), task, Checked<SimInstrumentConfig>{checked(std::move(config))}) {}

SimInstrument::SimInstrument(std::string name, TaskConfig task, Checked<SimInstrumentConfig> config)
    : Device(std::move(name), task, contract_of(config.value)), config_(std::move(config.value)) {
  q_ = setpoint_ = solved_ = config_.initial_joints;
  jaw_ = jaw_setpoint_ = jaw_goal_ = config_.initial_jaw;
  jaw_js_.size = 1;
  (void)jaw_js_.set_name(0, "jaw");
  publish(0);
  auto& a = crtk_interface();
  crtk::provide(a, crtk::arm::jaw_measured_js, state_table(), &jaw_js_);
  crtk::provide(a, crtk::arm::jaw_servo_jp, [this](const JointState& j) { on_jaw(j); });
  provide("instrument")
      .add_command_read("summary", state_table().add_column("summary", &summary_, ColumnUse::summary));
}

void SimInstrument::on_jaw(const JointState& j) noexcept {
  // Checked as the base checks a servo command: finite, within the jaw's limits, and only while
  // it follows (a disabled or faulted instrument's jaw stays where it is).
  if (j.size < 1 || !std::isfinite(j.position[0]) || j.position[0] < config_.jaw_min ||
      j.position[0] > config_.jaw_max || !following()) {
    ++summary_.jaw_refused;
    return;
  }
  ++summary_.jaw_goals;
  jaw_goal_ = j.position[0];
}

void SimInstrument::enter_safe_state(SafeReason) {
  setpoint_ = solved_ = q_;  // hold where it is
  jaw_setpoint_ = jaw_goal_ = jaw_;
}

Outcome SimInstrument::read() { return Outcome::done(); }

Outcome SimInstrument::write(const Setpoint& s) {
  const double dt = static_cast<double>(config().period.count()) * 1e-9;
  if (s.mode == ServoMode::cp) {
    ++summary_.poses;
    InstrumentKinematics::Joints q = solved_;
    if (!kinematics_.ik(isometry(s.pose), config_.joint_min, config_.joint_max, q)) ++summary_.unreachable;
    solved_ = q;
  } else {
    solved_ = setpoint_;  // no command: hold the setpoint (the base's safe output)
  }
  const InstrumentKinematics::Joints step = config_.max_velocity * dt;
  setpoint_ += (solved_ - setpoint_).cwiseMax(-step).cwiseMin(step);
  jaw_setpoint_ += std::clamp(jaw_goal_ - jaw_setpoint_, -config_.jaw_rate * dt, config_.jaw_rate * dt);
  const double follow = config_.servo_lag > 0 ? 1.0 - std::exp(-dt / config_.servo_lag) : 1.0;
  q_ += follow * (setpoint_ - q_);
  jaw_ += follow * (jaw_setpoint_ - jaw_);
  publish(dt);
  return Outcome::done();
}

void SimInstrument::publish(double dt) noexcept {
  const Eigen::Isometry3d now = kinematics_.fk(q_);
  Measured& m = measured();
  const Eigen::Quaterniond q(now.linear());
  m.cp.position = to_vec3(Eigen::Vector3d(now.translation()));
  m.cp.orientation = to_quat(q);
  if (dt > 0) {
    m.cv.linear = to_vec3(Eigen::Vector3d((now.translation() - pose_.translation()) / dt));
    m.cv.angular = to_vec3(angular_velocity(Eigen::Quaterniond(pose_.linear()), q, dt));
  }
  pose_ = now;
  for (int i = 0; i < InstrumentKinematics::dof; ++i) m.js.position[static_cast<std::size_t>(i)] = q_[i];
  jaw_js_.position[0] = jaw_;
}

}  // namespace saw::drivers
