#include "saw/drivers/falcon/sim_firmware.hpp"

#include <cmath>
#include <numbers>

namespace saw::drivers::falcon {

SimFalconFirmware::SimFalconFirmware(SimFirmwareConfig c)
    : config_(c), kinematics_(c.geometry), theta_(c.initial_angles) {
  origin_ = tip();
}

Eigen::Vector3d SimFalconFirmware::tip() const noexcept {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  (void)kinematics_.forward(theta_, x);
  return x;
}

void SimFalconFirmware::step(double dt) noexcept {
  const double t = t_;
  Eigen::Vector3d target = origin_ + hand_offset_;
  if (config_.hand)
    target += config_.hand_amplitude * std::sin(2 * std::numbers::pi * config_.hand_frequency * t);
  Eigen::Vector3d x;
  Eigen::Matrix3d j;
  if (!kinematics_.forward(theta_, x) || !kinematics_.jacobian(theta_, x, j)) j.setZero();
  const Eigen::Vector3d xd = j * theta_dot_;
  // The simulated operator takes the grip once the Falcon has homed (homing pushes the arms
  // against their stops: a hand holding the grip would stop it).
  const bool held = homed_[0] && homed_[1] && homed_[2] && !(control_ & control::homing);
  hand_force_ = held && (config_.hand || !hand_offset_.isZero())
                    ? Eigen::Vector3d(config_.hand_stiffness * (target - x) - config_.hand_damping * xd)
                    : Eigen::Vector3d::Zero();
  const Eigen::Vector3d tau = torque_ + j.transpose() * hand_force_ - config_.damping * theta_dot_;
  theta_dot_ += dt * tau / config_.inertia;  // semi-implicit Euler
  theta_ += dt * theta_dot_;
  for (int i = 0; i < 3; ++i) {  // the mechanical stops
    if (theta_[i] < config_.angle_min)
      theta_[i] = config_.angle_min, theta_dot_[i] = std::max(0.0, theta_dot_[i]);
    if (theta_[i] > config_.angle_max)
      theta_[i] = config_.angle_max, theta_dot_[i] = std::min(0.0, theta_dot_[i]);
    const auto k = static_cast<std::size_t>(i);
    if ((control_ & control::homing) && theta_[i] <= config_.index_angle) homed_[k] = true;
  }
  t_ += dt;
}

Packet SimFalconFirmware::answer(const Packet& command) noexcept {
  MotorCommand c{};
  if (decode_command(command, c) == FrameError::none) {
    control_ = c.control;
    torque_ = kinematics_.torque(c.dac);
  } else {
    ++refused_;
    torque_.setZero();
  }
  const double h = config_.dt / config_.substeps;
  for (int s = 0; s < config_.substeps; ++s) step(h);
  DeviceReport r;
  for (std::size_t i = 0; i < 3; ++i) {
    const std::int16_t e = kinematics_.encoder(theta_[static_cast<Eigen::Index>(i)]);
    r.encoder[i] = homed_[i] ? e : static_cast<std::int16_t>(e - config_.power_up_offset[i]);
    if ((control_ & control::homing) && homed_[i])
      r.status = static_cast<std::uint8_t>(r.status | (1u << (status::homed_shift + i)));
  }
  r.status = static_cast<std::uint8_t>(r.status | buttons_);
  Packet p = encode_report(r);
  if (corrupt_ > 0) --corrupt_, p[7] = 'Z';
  return p;
}

ExchangeResult SimTransport::exchange(const Packet& out, Packet& in) noexcept {
  if (!open_ || firmware_->unplugged()) return {ExchangeStatus::disconnected, 0, 0};
  in = firmware_->answer(out);  // time passes for the arms whether or not the answer arrives
  if (firmware_->dropping()) return {ExchangeStatus::no_answer, 0, 0};
  return {ExchangeStatus::ok, packet_size, 0};
}

}  // namespace saw::drivers::falcon
