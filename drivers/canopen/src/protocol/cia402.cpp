#include "saw/canopen/cia402.hpp"

namespace saw::canopen::cia402 {

std::string_view to_string(State s) noexcept {
  switch (s) {
    case State::not_ready_to_switch_on:
      return "not ready to switch on";
    case State::switch_on_disabled:
      return "switch on disabled";
    case State::ready_to_switch_on:
      return "ready to switch on";
    case State::switched_on:
      return "switched on";
    case State::operation_enabled:
      return "operation enabled";
    case State::quick_stop_active:
      return "quick stop active";
    case State::fault_reaction_active:
      return "fault reaction active";
    case State::fault:
      return "fault";
    case State::unknown:
      return "unknown";
  }
  return "unknown";
}

State decode_state(std::uint16_t sw) noexcept {
  // Two masks: the states where the quick-stop bit is "x" are told apart by bits 0-3 and 6.
  switch (sw & 0x004F) {
    case 0x0000:
      return State::not_ready_to_switch_on;
    case 0x0040:
      return State::switch_on_disabled;
    case 0x000F:
      return State::fault_reaction_active;
    case 0x0008:
      return State::fault;
    default:
      break;
  }
  switch (sw & 0x006F) {
    case 0x0021:
      return State::ready_to_switch_on;
    case 0x0023:
      return State::switched_on;
    case 0x0027:
      return State::operation_enabled;
    case 0x0007:
      return State::quick_stop_active;
    default:
      return State::unknown;
  }
}

std::uint16_t state_statusword(State s) noexcept {
  switch (s) {
    case State::not_ready_to_switch_on:
      return 0x0000;
    case State::switch_on_disabled:
      return 0x0040;
    case State::ready_to_switch_on:
      return 0x0021;
    case State::switched_on:
      return 0x0023;
    case State::operation_enabled:
      return 0x0027;
    case State::quick_stop_active:
      return 0x0007;
    case State::fault_reaction_active:
      return 0x000F;
    case State::fault:
      return 0x0008;
    case State::unknown:
      return 0x0000;
  }
  return 0;
}

Command decode_command(std::uint16_t cw) noexcept {
  if ((cw & controlword::fault_reset) != 0) return Command::none;
  if ((cw & 0x0002) == 0) return Command::disable_voltage;                     // xx0x
  if ((cw & 0x0006) == 0x0002) return Command::quick_stop;                     // x01x
  if ((cw & 0x0007) == 0x0006) return Command::shutdown;                       // x110
  return (cw & 0x0008) != 0 ? Command::enable_operation : Command::switch_on;  // 1111 / 0111
}

std::string_view to_string(Command c) noexcept {
  switch (c) {
    case Command::none:
      return "none";
    case Command::shutdown:
      return "shutdown";
    case Command::switch_on:
      return "switch on";
    case Command::enable_operation:
      return "enable operation";
    case Command::disable_voltage:
      return "disable voltage";
    case Command::quick_stop:
      return "quick stop";
  }
  return "unknown";
}

std::string_view to_string(Mode m) noexcept {
  switch (m) {
    case Mode::none:
      return "no mode";
    case Mode::profile_position:
      return "profile position";
    case Mode::velocity:
      return "velocity";
    case Mode::profile_velocity:
      return "profile velocity";
    case Mode::profile_torque:
      return "profile torque";
    case Mode::homing:
      return "homing";
    case Mode::interpolated_position:
      return "interpolated position";
    case Mode::cyclic_synchronous_position:
      return "cyclic synchronous position";
    case Mode::cyclic_synchronous_velocity:
      return "cyclic synchronous velocity";
    case Mode::cyclic_synchronous_torque:
      return "cyclic synchronous torque";
  }
  return static_cast<std::int8_t>(m) < 0 ? "manufacturer-specific mode" : "reserved mode";
}

std::uint32_t supported_mode_bit(Mode m) noexcept {
  const auto v = static_cast<std::int8_t>(m);
  // 0x6502: bit 0 profile position .. bit 9 cyclic synchronous torque; mode 5 is reserved.
  if (v < 1 || v > 10 || v == 5) return 0;
  return std::uint32_t{1} << (v - 1);
}

}  // namespace saw::canopen::cia402
