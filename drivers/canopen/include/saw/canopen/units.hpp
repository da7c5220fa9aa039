// Drive units and SI: counts to radians or metres, per mille of rated torque to newton-metres.
#pragma once

#include <cstdint>
#include <numbers>

#include "saw/canopen/od.hpp"

namespace saw::canopen {

// One axis: a rotary joint (radians) or a linear one through a screw or belt (metres). All
// conversions are checked: a non-finite value is invalid, one beyond the drive's integer type
// is too high or too low, and nothing is silently wrapped or clamped.
struct DriveUnits {
  double counts_per_revolution = 0;                 // encoder increments per motor revolution (0x608F)
  double gear_ratio = 1;                            // motor revolutions per output revolution (0x6091)
  double si_per_revolution = 2 * std::numbers::pi;  // output travel per revolution: 2π rad, or a lead in m
  double rated_torque = 0;  // motor rated torque in N·m (0x6076 holds mN·m); the 1000 ‰ of 0x6071

  static DriveUnits rotary(double counts_per_revolution, double gear_ratio, double rated_torque_nm);
  static DriveUnits linear(double counts_per_revolution, double gear_ratio, double lead_m,
                           double rated_torque_nm);
  // Set-up: throws std::invalid_argument unless every factor is finite and above 0.
  void check() const;

  double counts_per_si() const noexcept { return counts_per_revolution * gear_ratio / si_per_revolution; }

  // Position (0x607A target, 0x6064 actual: INTEGER32 counts).
  Codec position_to_counts(double si, std::int32_t& counts) const noexcept;
  double counts_to_position(std::int32_t counts) const noexcept { return counts / counts_per_si(); }
  // Velocity (0x60FF target, 0x606C actual: INTEGER32 counts per second, the default
  // velocity unit when the velocity factor 0x6096 is 1).
  Codec velocity_to_counts(double si_per_s, std::int32_t& counts_per_s) const noexcept;
  double counts_to_velocity(std::int32_t counts_per_s) const noexcept {
    return counts_per_s / counts_per_si();
  }
  // Motor torque (0x6071 target, 0x6077 actual: INTEGER16 per mille of the rated torque).
  Codec torque_to_per_mille(double nm, std::int16_t& per_mille) const noexcept;
  double per_mille_to_torque(std::int16_t per_mille) const noexcept {
    return per_mille * rated_torque / 1000.0;
  }
  // The same at the joint: effort at the output (N·m for a rotary joint, N for a linear one)
  // through the gear (and the lead), an ideal transmission without friction.
  double effort_per_motor_torque() const noexcept {
    return gear_ratio * 2 * std::numbers::pi / si_per_revolution;
  }
  Codec effort_to_per_mille(double effort, std::int16_t& per_mille) const noexcept {
    return torque_to_per_mille(effort / effort_per_motor_torque(), per_mille);
  }
  double per_mille_to_effort(std::int16_t per_mille) const noexcept {
    return per_mille_to_torque(per_mille) * effort_per_motor_torque();
  }
};

}  // namespace saw::canopen
