// The simulated drive's motor and load: a rigid rotor behind a gear, and the servo loops a drive runs.
#pragma once

#include <cstdint>

#include "saw/clock.hpp"

namespace saw::canopen::sim {

// Defaults: a 100 W class servo motor (0.32 N·m rated) with a small arm behind a 100:1 gear.
struct MotorParameters {
  double motor_inertia = 2.0e-5;      // kg·m², the rotor
  double load_inertia = 0.05;         // kg·m² at the output shaft; the motor sees it divided by the ratio²
  double viscous_friction = 2.0e-4;   // N·m·s/rad at the motor shaft
  double load_torque = 0.0;           // N·m at the output shaft, constant (a weight held up)
  double position_bandwidth_hz = 25;  // CSP: the drive's position loop (proportional)
  double velocity_bandwidth_hz = 150;  // CSP and CSV: the velocity loop (PI, critically damped)
  TimeNs integration_step = 50'000;    // the model's own step, whatever the caller's period

  // Set-up: throws std::invalid_argument naming the first parameter that is not finite, is
  // negative, or (inertia, bandwidths, step) is not above 0; a position loop faster than a
  // quarter of the velocity loop is refused too (the cascade would ring).
  void check() const;
};

// What the drive's control asks of the motor until the next step.
struct ServoCommand {
  enum class Loop : std::uint8_t {
    off,       // power stage off: no torque, the load coasts
    torque,    // CST: `torque`
    velocity,  // CSV, and stopping (quick stop, fault reaction): `velocity`
    position,  // CSP: `position` moving at `velocity` (the feed-forward) from the step's start
  };
  Loop loop = Loop::off;
  double position = 0;    // rad at the motor
  double velocity = 0;    // rad/s at the motor
  double torque = 0;      // N·m at the motor
  double max_torque = 0;  // N·m: the most the power stage gives (0x6072), either sign
};

// J·dω/dt = τ − b·ω − τ_load/N, with J = J_motor + J_load/N², integrated with semi-implicit
// Euler at a fixed step so that the result does not depend on how often the caller steps.
// The velocity loop is τ = J·(Kv·e + Ki·∫e) with Kv = 2π·f_v and Ki = Kv²/4: a double pole at
// −Kv/2 (the PI's zero still makes a step overshoot by about a tenth; CSP's feed-forward keeps
// ramps clean); its integral stops while the torque saturates.
// The position loop in front of it adds Kp·(p_ref − θ), Kp = 2π·f_p, to the feed-forward.
// No allocation, no exception after construction.
class MotorModel {
 public:
  explicit MotorModel(const MotorParameters& p);  // throws as MotorParameters::check()

  // Motor revolutions per output revolution (0x6091): changes the reflected load.
  void set_gear_ratio(double ratio) noexcept;
  // Advances by `dt` with `command` held. A `dt` beyond a second (a stalled caller) is cut to
  // one: the model never spends unbounded time catching up.
  void advance(const ServoCommand& command, TimeNs dt) noexcept;
  // Forgets the velocity loop's integral: on a change of loop, and whenever power goes off.
  void reset_servo() noexcept { integral_ = 0; }

  double position() const noexcept { return position_; }  // rad at the motor
  double velocity() const noexcept { return velocity_; }  // rad/s at the motor
  double torque() const noexcept { return torque_; }      // N·m the motor applied last
  double inertia() const noexcept { return inertia_; }    // kg·m² seen by the motor
  const MotorParameters& parameters() const noexcept { return p_; }

 private:
  double servo_torque(const ServoCommand& c, double elapsed, double dt) noexcept;

  MotorParameters p_;
  double ratio_ = 1;
  double inertia_ = 0;
  double kp_ = 0, kv_ = 0, ki_ = 0;
  double position_ = 0, velocity_ = 0, torque_ = 0;
  double integral_ = 0;  // the velocity loop's ∫e, rad
};

}  // namespace saw::canopen::sim
