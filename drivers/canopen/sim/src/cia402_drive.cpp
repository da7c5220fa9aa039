#include "saw/canopen/cia402_drive.hpp"

namespace saw::canopen::cia402 {

State Drive::update(const DriveInput& in) noexcept {
  const bool reset_edge = (in.controlword & controlword::fault_reset) != 0 &&
                          (previous_controlword_ & controlword::fault_reset) == 0;
  previous_controlword_ = in.controlword;
  voltage_ = in.voltage;
  const Command c = decode_command(in.controlword);

  if (in.fault && state_ != State::fault_reaction_active && state_ != State::fault) {
    go(State::fault_reaction_active, 13);
    return state_;
  }
  switch (state_) {
    case State::not_ready_to_switch_on:
      go(State::switch_on_disabled, 1);
      break;
    case State::switch_on_disabled:
      if (c == Command::shutdown) go(State::ready_to_switch_on, 2);
      break;
    case State::ready_to_switch_on:
      if (c == Command::switch_on || c == Command::enable_operation) {
        go(State::switched_on, 3);  // "switch on + enable operation" continues with 4 next cycle
      } else if (c == Command::disable_voltage || c == Command::quick_stop) {
        go(State::switch_on_disabled, 7);
      }
      break;
    case State::switched_on:
      if (c == Command::enable_operation) {
        go(State::operation_enabled, 4);
      } else if (c == Command::shutdown) {
        go(State::ready_to_switch_on, 6);
      } else if (c == Command::disable_voltage || c == Command::quick_stop) {
        go(State::switch_on_disabled, 10);
      }
      break;
    case State::operation_enabled:
      if (c == Command::switch_on) {
        go(State::switched_on, 5);  // disable operation
      } else if (c == Command::shutdown) {
        go(State::ready_to_switch_on, 8);
      } else if (c == Command::disable_voltage) {
        go(State::switch_on_disabled, 9);
      } else if (c == Command::quick_stop) {
        go(State::quick_stop_active, 11);
        // Option 0 disables the drive function at once: no ramp to wait for.
        if (config_.quick_stop_option == 0) go(State::switch_on_disabled, 12);
      }
      break;
    case State::quick_stop_active:
      if (c == Command::disable_voltage) {
        go(State::switch_on_disabled, 12);
      } else if (quick_stop_stays_active(config_.quick_stop_option)) {
        if (c == Command::enable_operation) go(State::operation_enabled, 16);
      } else if (in.standstill) {
        go(State::switch_on_disabled, 12);  // the quick stop is complete
      }
      break;
    case State::fault_reaction_active:
      if (in.standstill) go(State::fault, 14);  // the reaction is complete
      break;
    case State::fault:
      if (reset_edge && !in.fault) go(State::switch_on_disabled, 15);
      break;
    case State::unknown:
      go(State::fault, 13);
      break;
  }
  return state_;
}

std::uint16_t Drive::statusword() const noexcept {
  return static_cast<std::uint16_t>(state_statusword(state_) | (voltage_ ? statusword::voltage_enabled : 0) |
                                    statusword::remote | extra_bits_);
}

bool Drive::request_mode(Mode m) noexcept {
  if ((supported_mode_bit(m) & config_.supported_modes) == 0) return false;
  mode_ = m;
  return true;
}

}  // namespace saw::canopen::cia402
