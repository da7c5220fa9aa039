#include "saw/drivers/sim_haptic_device.hpp"

#include <cmath>
#include <stdexcept>

#include "saw/drivers/falcon/delta_dynamics.hpp"
#include "saw/drivers/falcon/delta_kinematics.hpp"
#include "saw/eigen.hpp"
#include "saw/log.hpp"

namespace saw::drivers {
namespace {

// Fills the model's defaults where the configuration left zeros.
SimDeviceConfig with_defaults(SimDeviceConfig c, const TaskConfig& task) {
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
  if (c.max_force <= 0) c.max_force = omni ? 3.3 : 9.0;
  if (c.substeps < 1) c.substeps = 1;
  if (c.command_timeout == 0) c.command_timeout = 3 * task.period.count();
  if (c.command_timeout < task.period.count())
    throw std::invalid_argument("command_timeout must be at least one period");
  // The straight Omni arm is singular: by default start with the elbow bent. The Falcon starts
  // with its arms at 35°, where its measured_cp is zero.
  if (omni && c.initial_joints.isZero()) c.initial_joints = Eigen::Vector3d(0, 0, 1.2);
  if (!omni && c.initial_joints.isZero())
    c.initial_joints = Eigen::Vector3d::Constant(falcon::DeltaGeometry{}.angle_at_zero);
  if ((c.inertia.array() <= 0).any()) throw std::invalid_argument("inertia must be positive");
  if ((c.joint_min.array() > c.joint_max.array()).any()) throw std::invalid_argument("joint_min > joint_max");
  return c;
}

}  // namespace

SimHapticDevice::SimHapticDevice(std::string name, TaskConfig task, SimDeviceConfig config)
    : Task(std::move(name), task),
      config_(with_defaults(std::move(config), task)),
      kinematics_(config_.model) {
  if (!task.is_periodic())
    throw std::invalid_argument("SimHapticDevice '" + this->name() + "' must be periodic");
  q_ = config_.initial_joints.cwiseMax(config_.joint_min).cwiseMin(config_.joint_max);
  hand_origin_ = kinematics_.fk(q_);
  measured_js_.size = 3;
  const auto names = kinematics_.joint_names();
  for (std::size_t i = 0; i < names.size(); ++i)
    if (!measured_js_.set_name(i, names[i])) throw std::logic_error("joint name too long");
  operating_state_.state =
      config_.start_enabled ? OperatingStateValue::enabled : OperatingStateValue::disabled;
  publish();

  auto& st = state_table();
  columns_.hand_force = st.add_column("hand_force", &hand_force_);
  columns_.servo_force = st.add_column("servo_force", &servo_force_);
  watchdog_.set_timeout(config_.command_timeout);
  columns_.command_timeout = watchdog_.holding_column();
  columns_.watchdog_trips = watchdog_.trips_column();
  st.add_column("summary", &summary_, ColumnUse::summary);
  namespace arm_if = crtk::arm;
  auto& arm = provide(std::string(arm_if::interface_name));
  columns_.measured_cp = crtk::provide(arm, arm_if::measured_cp, st, &measured_cp_);
  columns_.measured_cv = crtk::provide(arm, arm_if::measured_cv, st, &measured_cv_);
  columns_.measured_js = crtk::provide(arm, arm_if::measured_js, st, &measured_js_);
  crtk::provide(arm, arm_if::operating_state, st, &operating_state_);
  arm.add_command_read("servo_force", columns_.servo_force);
  arm.add_command_read("command_timeout", columns_.command_timeout);
  arm.add_command_read("watchdog_trips", columns_.watchdog_trips);
  crtk::provide(arm, arm_if::servo_cf, [this](const Wrench& w) { servo_cf(w); });
  // Declared for callers outside the host (the gateway checks it); servo_cf() checks the norm.
  arm.limit(arm_if::servo_cf.name, -config_.max_force, config_.max_force);
  crtk::provide(arm, arm_if::state_command, [this](const StateCommand& c) { state_command(c); });
  state_event_ = &crtk::provide(arm, arm_if::operating_state_event);
  clutch_event_ = &crtk::provide(arm, arm_if::clutch);
  operator_event_ = &crtk::provide(arm, arm_if::operator_present);
  auto& sim = provide("sim");
  sim.add_command_write<ButtonCommand>("set_button",
                                       [this](const ButtonCommand& b) { button(b.button, b.pressed); });
  sim.add_command_read("hand_force", columns_.hand_force);
  sim.add_command_read("rejected_commands", st.add_column("rejected_commands", &rejected_column_));
}

void SimHapticDevice::servo_cf(const Wrench& w) noexcept {
  watchdog_.commanded(now());  // a refused command is fresh too: it zeroes the force itself
  const Eigen::Vector3d f(w.force[0], w.force[1], w.force[2]);
  if (!f.allFinite() || f.norm() > config_.max_force) {
    // Never let a bad command reach the motors, nor keep pushing with the last good one.
    force_.setZero();
    ++rejected_;
    return;
  }
  force_ = f;
}

void SimHapticDevice::watch_commands() noexcept {
  if (!watchdog_.expired(now())) return;
  force_.setZero();
  saw::log(LogLevel::warning, name().c_str(), "no servo_cf for {} ns: force dropped to zero",
           now() - watchdog_.last_command());
}

void SimHapticDevice::set_state(OperatingStateValue s) noexcept {
  if (operating_state_.state == s) return;
  operating_state_.state = s;
  (void)(*state_event_)(operating_state_);
}

void SimHapticDevice::state_command(StateCommand c) noexcept {
  switch (c) {
    case StateCommand::enable:
      set_state(OperatingStateValue::enabled);
      break;
    case StateCommand::disable:
      set_state(OperatingStateValue::disabled);
      break;
    case StateCommand::pause:
      if (operating_state_.state == OperatingStateValue::enabled) set_state(OperatingStateValue::paused);
      break;
    case StateCommand::resume:
      if (operating_state_.state == OperatingStateValue::paused) set_state(OperatingStateValue::enabled);
      break;
    case StateCommand::home:
      if (!operating_state_.is_homed) {
        operating_state_.is_homed = true;
        (void)(*state_event_)(operating_state_);
      }
      break;
  }
}

void SimHapticDevice::button(std::uint8_t id, bool pressed) noexcept {
  if (id == 0) (void)(*clutch_event_)(ButtonEvent{pressed});
  if (id == 1) (void)(*operator_event_)(ButtonEvent{pressed});
}

void SimHapticDevice::integrate(double dt, const Eigen::Vector3d& hand_target) noexcept {
  const bool powered = operating_state_.state == OperatingStateValue::enabled;
  const Eigen::Vector3d servo = powered ? force_ : Eigen::Vector3d::Zero();
  Eigen::Vector3d hand = Eigen::Vector3d::Zero();
  for (int i = 0; i < config_.substeps; ++i) {
    const Eigen::Vector3d x = kinematics_.fk(q_);
    const Eigen::Matrix3d j = kinematics_.jacobian(q_);
    const Eigen::Vector3d xd = j * qd_;
    hand = config_.hand.kind == HandScript::Kind::none
               ? Eigen::Vector3d::Zero()
               : Eigen::Vector3d(config_.hand.stiffness * (hand_target - x) - config_.hand.damping * xd);
    const Eigen::Vector3d tau = j.transpose() * (servo + hand);  // τ = Jᵀ·f
    const Eigen::Vector3d qdd = (tau - config_.damping.cwiseProduct(qd_)).cwiseQuotient(config_.inertia);
    qd_ += dt * qdd;  // semi-implicit Euler
    q_ += dt * qd_;
    for (int k = 0; k < 3; ++k) {  // hard stops
      if (q_[k] < config_.joint_min[k]) q_[k] = config_.joint_min[k], qd_[k] = std::max(0.0, qd_[k]);
      if (q_[k] > config_.joint_max[k]) q_[k] = config_.joint_max[k], qd_[k] = std::min(0.0, qd_[k]);
    }
  }
  hand_force_ = to_vec3(hand);
  servo_force_ = to_vec3(servo);
}

void SimHapticDevice::publish() noexcept {
  const Eigen::Vector3d x = kinematics_.fk(q_);
  const Eigen::Vector3d xd = kinematics_.jacobian(q_) * qd_;
  measured_cp_.position = to_vec3(x);
  measured_cv_.linear = to_vec3(xd);
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    measured_js_.position[i] = q_[k];
    measured_js_.velocity[i] = qd_[k];
  }
  rejected_column_ = rejected_;
  summary_ = {rejected_, watchdog_.trips(), config_.command_timeout};
}

void SimHapticDevice::run() {
  if (t0_ < 0) t0_ = now();
  const double t = static_cast<double>(now() - t0_) * 1e-9;
  const HandSample h = config_.hand.target(t, hand_cursor_);
  if (config_.hand.kind == HandScript::Kind::csv && h.clutch != hand_clutch_) {
    hand_clutch_ = h.clutch;
    button(0, h.clutch);
  }
  watch_commands();
  const double dt = static_cast<double>(config().period.count()) * 1e-9 / config_.substeps;
  integrate(dt, hand_origin_ + h.position);
  publish();
}

}  // namespace saw::drivers
