// The drive side of CiA 402 for the simulated drive: every transition of the state machine figure.
#pragma once

#include <cstdint>

#include "saw/canopen/cia402.hpp"

namespace saw::canopen::cia402 {

struct DriveConfig {
  std::int16_t quick_stop_option = 2;  // 0x605A
  // Modes the drive accepts (0x6502 bits); CSP, CSV and CST by default.
  std::uint32_t supported_modes = supported_mode_bit(csp) | supported_mode_bit(csv) | supported_mode_bit(cst);
};

// What the rest of the simulated drive tells the state machine each cycle.
struct DriveInput {
  std::uint16_t controlword = 0;
  bool fault = false;      // a fault condition is present (over-current, following error ...)
  bool standstill = true;  // the motion has stopped: ends a quick stop or a fault reaction
  bool voltage = true;     // the DC link is powered (statusword bit 4)
};

// Starts in not ready to switch on (transition 0); its first update() is the end of its
// self-test (transition 1). No allocation, no exception.
class Drive {
 public:
  explicit Drive(DriveConfig config = {}) noexcept : config_(config) {}

  State update(const DriveInput& in) noexcept;

  State state() const noexcept { return state_; }
  // The statusword: the state's bits, voltage enabled, remote, and the bits set_status_bits() gave.
  std::uint16_t statusword() const noexcept;
  // The number (0..16) of the last transition taken in the CiA 402 figure; 13 for fault entry.
  int last_transition() const noexcept { return last_transition_; }
  // Whether the drive applies torque and follows setpoints (operation enabled), and whether its
  // power stage is on at all (also while stopping: quick stop active, fault reaction active).
  bool following() const noexcept { return state_ == State::operation_enabled; }
  bool powered() const noexcept {
    return state_ == State::switched_on || state_ == State::operation_enabled ||
           state_ == State::quick_stop_active || state_ == State::fault_reaction_active;
  }

  // Bits the rest of the drive sets: warning, target reached, internal limit, mode-specific.
  void set_status_bits(std::uint16_t bits) noexcept { extra_bits_ = bits & 0xFC80; }
  // 0x6060 written: accepted if supported (0x6061 then shows it), else the display stays.
  bool request_mode(Mode m) noexcept;
  Mode mode_display() const noexcept { return mode_; }

 private:
  void go(State s, int transition) noexcept {
    state_ = s;
    last_transition_ = transition;
  }

  DriveConfig config_;
  State state_ = State::not_ready_to_switch_on;
  int last_transition_ = 0;
  std::uint16_t previous_controlword_ = 0;
  std::uint16_t extra_bits_ = 0;
  bool voltage_ = true;
  Mode mode_ = Mode::none;
};

}  // namespace saw::canopen::cia402
