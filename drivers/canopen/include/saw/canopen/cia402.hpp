// CiA 402 basics both sides share: drive states, statusword and controlword coding, modes, objects.
#pragma once

#include <cstdint>
#include <string_view>

#include "saw/canopen/od.hpp"

namespace saw::canopen::cia402 {

// The states of the power drive system (CiA 402 figure "state machine"), plus unknown for a
// statusword that is none of them.
enum class State : std::uint8_t {
  not_ready_to_switch_on,
  switch_on_disabled,
  ready_to_switch_on,
  switched_on,
  operation_enabled,
  quick_stop_active,
  fault_reaction_active,
  fault,
  unknown,
};
std::string_view to_string(State s) noexcept;

namespace statusword {
inline constexpr std::uint16_t ready_to_switch_on = 0x0001;
inline constexpr std::uint16_t switched_on = 0x0002;
inline constexpr std::uint16_t operation_enabled = 0x0004;
inline constexpr std::uint16_t fault = 0x0008;
inline constexpr std::uint16_t voltage_enabled = 0x0010;
inline constexpr std::uint16_t quick_stop = 0x0020;  // 0: a quick stop is in progress
inline constexpr std::uint16_t switch_on_disabled = 0x0040;
inline constexpr std::uint16_t warning = 0x0080;
inline constexpr std::uint16_t remote = 0x0200;
inline constexpr std::uint16_t target_reached = 0x0400;
inline constexpr std::uint16_t internal_limit_active = 0x0800;
inline constexpr std::uint16_t mode_specific_12 = 0x1000;  // CSP/CSV/CST: drive follows the target
inline constexpr std::uint16_t mode_specific_13 = 0x2000;  // CSP: following error
// The bits that say the state (the rest are free for the mode and the manufacturer).
inline constexpr std::uint16_t state_bits = 0x006F;
}  // namespace statusword

// The state a statusword shows (CiA 402 table "state coding"), unknown for any other pattern.
State decode_state(std::uint16_t statusword) noexcept;
// The state bits a drive in `s` shows (quick-stop bit set where it is "x"), 0 for unknown.
std::uint16_t state_statusword(State s) noexcept;

namespace controlword {
inline constexpr std::uint16_t switch_on = 0x0001;
inline constexpr std::uint16_t enable_voltage = 0x0002;
inline constexpr std::uint16_t quick_stop = 0x0004;  // 0: quick stop
inline constexpr std::uint16_t enable_operation = 0x0008;
inline constexpr std::uint16_t fault_reset = 0x0080;  // acts on its rising edge
inline constexpr std::uint16_t halt = 0x0100;
// Bits the device-control commands leave to the mode and the manufacturer (4..6, 8..15).
inline constexpr std::uint16_t mode_bits = 0xFF70;

// The device-control commands (CiA 402 table "command coding").
inline constexpr std::uint16_t shutdown_command = 0x0006;
inline constexpr std::uint16_t switch_on_command = 0x0007;         // also "disable operation"
inline constexpr std::uint16_t enable_operation_command = 0x000F;  // also "switch on + enable operation"
inline constexpr std::uint16_t disable_voltage_command = 0x0000;
inline constexpr std::uint16_t quick_stop_command = 0x0002;
}  // namespace controlword

// A controlword's command, as a drive reads it. switch_on is also disable operation and
// enable_operation also switch on + enable operation: which one it is depends on the state.
// With bit 7 set no command is read (only the fault-reset edge counts).
enum class Command : std::uint8_t {
  none,
  shutdown,
  switch_on,
  enable_operation,
  disable_voltage,
  quick_stop
};
Command decode_command(std::uint16_t controlword) noexcept;
std::string_view to_string(Command c) noexcept;

// Modes of operation (0x6060, displayed in 0x6061). Manufacturer modes are negative; any
// int8 value can be carried.
enum class Mode : std::int8_t {
  none = 0,
  profile_position = 1,
  velocity = 2,
  profile_velocity = 3,
  profile_torque = 4,
  homing = 6,
  interpolated_position = 7,
  cyclic_synchronous_position = 8,
  cyclic_synchronous_velocity = 9,
  cyclic_synchronous_torque = 10,
};
inline constexpr Mode csp = Mode::cyclic_synchronous_position;
inline constexpr Mode csv = Mode::cyclic_synchronous_velocity;
inline constexpr Mode cst = Mode::cyclic_synchronous_torque;
std::string_view to_string(Mode m) noexcept;
// The mode's bit in 0x6502 (supported drive modes); 0 for a mode without one.
std::uint32_t supported_mode_bit(Mode m) noexcept;

// Quick stop option code (0x605A): 0 disables the drive at once; 1..4 stop (slow-down ramp,
// quick-stop ramp, current limit, voltage limit) then switch on disabled; 5..8 the same ramps
// but stay in quick stop active.
inline constexpr bool quick_stop_stays_active(std::int16_t option) noexcept {
  return option >= 5 && option <= 8;
}

// The objects of a CiA 402 servo drive's first axis.
namespace object {
inline constexpr ObjectAddress abort_connection_option_code{0x6007, 0};
inline constexpr ObjectAddress error_code{0x603F, 0};
inline constexpr ObjectAddress controlword{0x6040, 0};
inline constexpr ObjectAddress statusword{0x6041, 0};
inline constexpr ObjectAddress quick_stop_option_code{0x605A, 0};
inline constexpr ObjectAddress modes_of_operation{0x6060, 0};
inline constexpr ObjectAddress modes_of_operation_display{0x6061, 0};
inline constexpr ObjectAddress position_actual_value{0x6064, 0};
inline constexpr ObjectAddress following_error_window{0x6065, 0};
inline constexpr ObjectAddress velocity_actual_value{0x606C, 0};
inline constexpr ObjectAddress target_torque{0x6071, 0};
inline constexpr ObjectAddress max_torque{0x6072, 0};
inline constexpr ObjectAddress motor_rated_torque{0x6076, 0};
inline constexpr ObjectAddress torque_actual_value{0x6077, 0};
inline constexpr ObjectAddress target_position{0x607A, 0};
inline constexpr ObjectAddress position_encoder_resolution_increments{0x608F, 1};
inline constexpr ObjectAddress position_encoder_resolution_revolutions{0x608F, 2};
inline constexpr ObjectAddress gear_ratio_motor_revolutions{0x6091, 1};
inline constexpr ObjectAddress gear_ratio_shaft_revolutions{0x6091, 2};
inline constexpr ObjectAddress interpolation_time_period_value{0x60C2, 1};
inline constexpr ObjectAddress interpolation_time_period_index{0x60C2, 2};
inline constexpr ObjectAddress target_velocity{0x60FF, 0};
inline constexpr ObjectAddress supported_drive_modes{0x6502, 0};
}  // namespace object

}  // namespace saw::canopen::cia402
