#include "saw/teleop/passivity_port.hpp"

#include <cmath>
#include <stdexcept>

#include "saw/eigen.hpp"
#include "saw/teleop/wave.hpp"

namespace saw::teleop {

PassivityPort::PassivityPort(std::string name, TaskConfig task, PortConfig config)
    : Task(std::move(name), task), config_(config), pc_(config.passivity ? config.max_damping : 0.0) {
  if (task.period.count() <= 0) throw std::invalid_argument("a passivity port must be periodic");
  if (!(config_.max_damping >= 0))
    throw std::invalid_argument("a passivity port's max_damping must not be negative");
  if (config_.command_hold <= 0) config_.command_hold = 5 * task.period.count();
  if (!(config_.wave_impedance > 0) || !std::isfinite(config_.wave_impedance))
    throw std::invalid_argument("a passivity port's wave_impedance must be positive and finite");
  if (!(config_.force_limit >= 0) || !std::isfinite(config_.force_limit))
    throw std::invalid_argument("a passivity port's force_limit must be finite and not negative");
  namespace arm = crtk::arm;
  auto& st = state_table();
  auto& p = provide(std::string(arm::interface_name));
  crtk::provide(p, arm::measured_cp, st, &cp_);
  crtk::provide(p, arm::measured_cv, st, &cv_);
  crtk::provide(p, port::energy, st, &energy_in_);
  crtk::provide(p, arm::servo_cf, [this](const Wrench& w) { on_command(w); });
  crtk::provide(p, port::remote_energy, [this](const double& e) { on_remote_energy(e); });
  crtk::provide(p, port::wave, st, &wave_out_);
  crtk::provide(p, port::remote_wave, [this](const Vec3& v) { on_remote_wave(v); });
  const double impedance = config_.scheme == PortScheme::wave ? config_.wave_impedance : 0.0;
  p.add_command_read_value<double>(std::string(port::wave_impedance.name), [impedance](double& out) noexcept {
    out = impedance;
    return Status::ok;
  });
  // What the controller did, for the recorder and a GUI.
  p.add_command_read("port_energy_out", st.add_column("port_energy_out", &energy_out_));
  p.add_command_read("port_dissipated", st.add_column("port_dissipated", &dissipated_));
  p.add_command_read("port_damping", st.add_column("port_damping", &damping_));
  p.add_command_read("port_remote_in", st.add_column("port_remote_in", &remote_shown_));
  p.add_command_read("port_applied", st.add_column("port_applied", &applied_));
  clutch_ = &crtk::provide(p, arm::clutch);
  operator_present_ = &crtk::provide(p, arm::operator_present);

  auto& r = require("device");
  crtk::require(r, arm::measured_cp, read_cp_);
  crtk::require(r, arm::measured_cv, read_cv_);
  crtk::require(r, arm::servo_cf, write_cf_);
  crtk::require(
      r, arm::clutch, [this](const ButtonEvent& b) { (void)(*clutch_)(b); }, Need::optional);
  crtk::require(
      r, arm::operator_present, [this](const ButtonEvent& b) { (void)(*operator_present_)(b); },
      Need::optional);
}

void PassivityPort::on_command(const Wrench& w) noexcept {
  if (!to_eigen(w.force).allFinite()) return void(++rejected_);
  pending_ = w;
  has_pending_ = true;
}

void PassivityPort::on_remote_energy(double e) noexcept {
  if (!std::isfinite(e) || e < 0) return void(++rejected_);
  // Energies only grow: an older value arriving late tells nothing new (and less is safe).
  if (e > remote_in_) remote_in_ = e;
}

void PassivityPort::on_remote_wave(const Vec3& v) noexcept {
  if (!to_eigen(v).allFinite()) return void(++rejected_);
  pending_wave_ = to_eigen(v);
  has_wave_ = true;
}

void PassivityPort::run() {
  Pose cp;
  Twist cv;
  RowStamp stamp;
  bool fresh = read_cp_(cp, stamp) == Status::ok && read_cv_(cv) == Status::ok;
  fresh = fresh && to_eigen(cp.position).allFinite() && to_eigen(cv.linear).allFinite();
  if (fresh) {
    cp_ = cp;
    cv_ = cv;
    device_time_ = stamp.time;
  }
  // The row stands for the device's reading: a device that stopped publishing ages here too.
  stamp_row(device_time_);
  const Eigen::Vector3d velocity = to_eigen(cv_.linear);
  if (config_.scheme == PortScheme::wave)
    apply_wave(velocity);
  else
    apply_passivity(velocity, static_cast<double>(config().period.count()) * 1e-9);
}

void PassivityPort::apply_passivity(const Eigen::Vector3d& velocity, double dt) noexcept {
  const TimeNs t = now();
  if (has_pending_) {
    held_ = to_eigen(pending_.force);
    held_since_ = t;
    has_pending_ = false;
  }
  const bool commanding = held_since_ >= 0 && t - held_since_ <= config_.command_hold;
  if (!commanding) return;  // the device's watchdog takes it from here
  // The power this cycle is the force applied now against the velocity now: only a device-side
  // observer sees both (the controller far away sees neither in time). Observing only, the
  // controller has no damping to give: its figures are the law's own.
  const Eigen::Vector3d f = pc_.step(held_, velocity, remote_in_, dt).force;
  Wrench w;
  w.force = to_vec3(f);
  (void)write_cf_(w);
  applied_ = w.force;
  energy_in_ = pc_.energy().in;
  energy_out_ = pc_.energy().out;
  dissipated_ = pc_.dissipated();
  damping_ = pc_.last_damping();
  remote_shown_ = remote_in_;
}

void PassivityPort::apply_wave(const Eigen::Vector3d& velocity) noexcept {
  const TimeNs t = now();
  // A cycle without a wave is a zero wave: a lost or late packet brings no energy.
  const Eigen::Vector3d v = has_wave_ ? pending_wave_ : Eigen::Vector3d::Zero();
  if (has_wave_) held_since_ = t;
  has_wave_ = false;
  has_pending_ = false;  // the force is made here
  const wave::MasterEnd end = wave::master_end(config_.wave_impedance, velocity, v, config_.force_limit);
  wave_out_ = to_vec3(end.u);
  if (held_since_ < 0 || t - held_since_ > config_.command_hold) return;
  Wrench w;
  w.force = to_vec3(end.force);
  (void)write_cf_(w);
  applied_ = w.force;
}

}  // namespace saw::teleop
