#include "saw/canopen/sim/motor_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace saw::canopen::sim {

namespace {
constexpr double two_pi = 2 * std::numbers::pi;
constexpr TimeNs longest_advance = 1'000'000'000;
}  // namespace

void MotorParameters::check() const {
  const auto require = [](bool ok, const char* name, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("motor model: ") + name + " " + what);
  };
  const auto finite = [](double v) { return std::isfinite(v); };
  require(finite(motor_inertia) && motor_inertia > 0, "motor_inertia", "must be above 0 (kg·m²)");
  require(finite(load_inertia) && load_inertia >= 0, "load_inertia", "must be 0 or more (kg·m²)");
  require(finite(viscous_friction) && viscous_friction >= 0, "viscous_friction",
          "must be 0 or more (N·m·s/rad)");
  require(finite(load_torque), "load_torque", "must be finite (N·m)");
  require(finite(velocity_bandwidth_hz) && velocity_bandwidth_hz > 0, "velocity_bandwidth_hz",
          "must be above 0");
  require(finite(position_bandwidth_hz) && position_bandwidth_hz > 0, "position_bandwidth_hz",
          "must be above 0");
  require(position_bandwidth_hz * 4 <= velocity_bandwidth_hz, "position_bandwidth_hz",
          "must be at most a quarter of velocity_bandwidth_hz");
  require(integration_step > 0 && integration_step <= 1'000'000, "integration_step", "must be 1 ns .. 1 ms");
  // Semi-implicit Euler on the velocity loop's double pole: stable for Kv·dt well below 2;
  // 0.5 keeps the discrete response within a few per cent of the continuous one.
  require(two_pi * velocity_bandwidth_hz * static_cast<double>(integration_step) * 1e-9 <= 0.5,
          "integration_step", "is too long for velocity_bandwidth_hz (2π·f·step must be at most 0.5)");
}

MotorModel::MotorModel(const MotorParameters& p) : p_(p) {
  p_.check();
  kv_ = two_pi * p_.velocity_bandwidth_hz;
  ki_ = kv_ * kv_ / 4;
  kp_ = two_pi * p_.position_bandwidth_hz;
  set_gear_ratio(1);
}

void MotorModel::set_gear_ratio(double ratio) noexcept {
  ratio_ = std::isfinite(ratio) && ratio > 0 ? ratio : 1;
  inertia_ = p_.motor_inertia + p_.load_inertia / (ratio_ * ratio_);
}

double MotorModel::servo_torque(const ServoCommand& c, double elapsed, double dt) noexcept {
  const double limit = std::isfinite(c.max_torque) ? std::max(0.0, c.max_torque) : 0.0;
  double demand = 0;
  switch (c.loop) {
    case ServoCommand::Loop::off:
      integral_ = 0;
      return 0;
    case ServoCommand::Loop::torque:
      return std::clamp(std::isfinite(c.torque) ? c.torque : 0.0, -limit, limit);
    case ServoCommand::Loop::velocity:
    case ServoCommand::Loop::position: {
      double target = c.velocity;
      if (c.loop == ServoCommand::Loop::position)
        target += kp_ * (c.position + c.velocity * elapsed - position_);
      const double error = target - velocity_;
      demand = inertia_ * (kv_ * error + ki_ * integral_);
      const double applied = std::clamp(demand, -limit, limit);
      // Conditional integration: while saturated, only an error that pulls out of saturation
      // is integrated, so the integral does not wind up during a long torque-limited move.
      if (applied == demand || (demand > applied) != (error > 0)) integral_ += error * dt;
      return applied;
    }
  }
  return 0;
}

void MotorModel::advance(const ServoCommand& command, TimeNs dt) noexcept {
  dt = std::min(dt, longest_advance);
  const double load = p_.load_torque / ratio_;
  TimeNs done = 0;
  while (done < dt) {
    const TimeNs h_ns = std::min(p_.integration_step, dt - done);
    const double h = static_cast<double>(h_ns) * 1e-9;
    torque_ = servo_torque(command, static_cast<double>(done) * 1e-9, h);
    const double acceleration = (torque_ - p_.viscous_friction * velocity_ - load) / inertia_;
    velocity_ += acceleration * h;
    position_ += velocity_ * h;
    done += h_ns;
  }
}

}  // namespace saw::canopen::sim
