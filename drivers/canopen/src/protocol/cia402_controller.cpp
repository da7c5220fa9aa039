#include "saw/canopen/cia402_controller.hpp"

namespace saw::canopen::cia402 {

std::string_view to_string(Target t) noexcept {
  switch (t) {
    case Target::switch_on_disabled:
      return "switch on disabled";
    case Target::ready_to_switch_on:
      return "ready to switch on";
    case Target::switched_on:
      return "switched on";
    case Target::operation_enabled:
      return "operation enabled";
    case Target::quick_stop:
      return "quick stop";
  }
  return "unknown";
}

std::string_view to_string(Progress p) noexcept {
  switch (p) {
    case Progress::reached:
      return "reached";
    case Progress::working:
      return "working";
    case Progress::fault:
      return "fault";
    case Progress::timeout:
      return "timeout";
    case Progress::unknown_state:
      return "unknown state";
  }
  return "unknown";
}

void Controller::set_target(Target t, TimeNs now) noexcept {
  if (t != target_) since_ = now;
  target_ = t;
}

void Controller::request_fault_reset(TimeNs now) noexcept {
  if (!reset_requested_) since_ = now;
  reset_requested_ = true;
  resets_ = 0;
}

bool Controller::reached(State s) const noexcept {
  switch (target_) {
    case Target::switch_on_disabled:
      return s == State::switch_on_disabled;
    case Target::ready_to_switch_on:
      return s == State::ready_to_switch_on;
    case Target::switched_on:
      return s == State::switched_on;
    case Target::operation_enabled:
      return s == State::operation_enabled;
    // Stopped either way: still in quick stop (option codes 5..8) or through to switch on
    // disabled (0..4), or never moving (no power stage on).
    case Target::quick_stop:
      return s == State::quick_stop_active || s == State::switch_on_disabled;
  }
  return false;
}

std::uint16_t Controller::command_for(State s) noexcept {
  using namespace controlword;
  if (s == State::fault) {
    if (!reset_requested_) return disable_voltage_command;
    // The edge: low (if it is not already), then high for a while, then low again to retry.
    if ((last_ & fault_reset) == 0) {
      if (resets_ >= config_.fault_reset_tries) {
        reset_requested_ = false;  // given up: the fault stays, and progress says so
        return disable_voltage_command;
      }
      ++resets_;
      reset_high_cycles_ = 1;
      return fault_reset;
    }
    if (reset_high_cycles_ < config_.fault_reset_cycles) {
      ++reset_high_cycles_;
      return fault_reset;
    }
    return disable_voltage_command;
  }
  if (target_ == Target::quick_stop) return quick_stop_command;
  if (target_ == Target::switch_on_disabled) return disable_voltage_command;
  switch (s) {
    case State::switch_on_disabled:
      return shutdown_command;  // transition 2
    case State::ready_to_switch_on:
      return target_ == Target::ready_to_switch_on ? shutdown_command : switch_on_command;  // 3
    case State::switched_on:
      switch (target_) {
        case Target::ready_to_switch_on:
          return shutdown_command;  // 6
        case Target::operation_enabled:
          return enable_operation_command;  // 4
        default:
          return switch_on_command;
      }
    case State::operation_enabled:
      switch (target_) {
        case Target::ready_to_switch_on:
          return shutdown_command;  // 8
        case Target::switched_on:
          return switch_on_command;  // 5 (disable operation)
        default:
          return enable_operation_command;
      }
    case State::quick_stop_active:
      return disable_voltage_command;  // 12, then up again from switch on disabled
    default:  // not ready to switch on, fault reaction active: automatic transitions only
      return disable_voltage_command;
  }
}

ControllerOutput Controller::update(std::uint16_t statusword, TimeNs now) noexcept {
  const State s = decode_state(statusword);
  if (!started_) {
    started_ = true;
    since_ = now;
    last_state_ = s;
  }
  if (s != last_state_) {
    since_ = now;
    last_state_ = s;
  }
  const bool in_fault = s == State::fault || s == State::fault_reaction_active;
  // A reset asked for outside fault has nothing to act on; one that succeeded is done.
  if (reset_requested_ && !in_fault && s != State::unknown) reset_requested_ = false;

  ControllerOutput out;
  out.state = s;
  out.in_state_for = now - since_;
  out.fault_resets = resets_;
  if (s == State::unknown) {
    out.controlword = last_;
    out.progress = Progress::unknown_state;
    return out;
  }
  const std::uint16_t command = command_for(s);
  // Mode bits only with a device-control command that is not the fault reset.
  last_ =
      (command & controlword::fault_reset) != 0 ? command : static_cast<std::uint16_t>(command | mode_bits_);
  out.controlword = last_;
  if (in_fault && !reset_requested_) {
    out.progress = Progress::fault;
  } else if (!in_fault && reached(s)) {
    out.progress = Progress::reached;
  } else {
    out.progress = out.in_state_for >= config_.transition_timeout ? Progress::timeout : Progress::working;
  }
  return out;
}

}  // namespace saw::canopen::cia402
