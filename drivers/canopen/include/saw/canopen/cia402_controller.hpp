// The master side of CiA 402: each cycle, the controlword that walks a drive towards a target state.
#pragma once

#include <cstdint>

#include "saw/canopen/cia402.hpp"
#include "saw/clock.hpp"

namespace saw::canopen::cia402 {

// Where the master wants the drive.
enum class Target : std::uint8_t {
  switch_on_disabled,  // power stage off, disable voltage (CRTK disabled)
  ready_to_switch_on,  // shutdown
  switched_on,         // power stage on, no torque
  operation_enabled,   // following setpoints (CRTK enabled)
  quick_stop,          // stopping on the quick-stop ramp, then as 0x605A says
};
std::string_view to_string(Target t) noexcept;

struct ControllerConfig {
  // A transition not seen within this long is reported (the controller keeps trying): drives
  // take a few ms per transition; the brake release on enable can take a few hundred.
  TimeNs transition_timeout = 1'000'000'000;
  // Cycles the fault-reset bit stays high before it drops for one cycle to make a new edge,
  // for a drive that missed the first one or whose fault was still present.
  int fault_reset_cycles = 8;
  // Rising edges of bit 7 sent to a drive that stays in fault before the reset is given up
  // (Progress::fault): a fault whose cause is still present is not reset forever.
  int fault_reset_tries = 3;
};

enum class Progress : std::uint8_t {
  reached,        // the drive is in the target state
  working,        // a transition is under way
  fault,          // the drive is in fault (or reacting to one): no reset asked for, or the tries used up
  timeout,        // no transition for transition_timeout
  unknown_state,  // the statusword is no CiA 402 state: the last controlword is held
};
std::string_view to_string(Progress p) noexcept;

// One cycle's answer, Ruckig's shape: what to send, and where things stand.
struct ControllerOutput {
  std::uint16_t controlword = 0;
  State state = State::unknown;
  Progress progress = Progress::working;
  TimeNs in_state_for = 0;  // time since the state (or the target) last changed
  int fault_resets = 0;     // rising edges of bit 7 sent since the last request_fault_reset()
};

// Pure and allocation-free: call update() once per cycle with the statusword just received;
// send the controlword it returns. It walks the standard path only (shutdown, switch on,
// enable operation) and leaves quick stop active through switch on disabled, which every
// quick-stop option code allows.
class Controller {
 public:
  explicit Controller(ControllerConfig config = {}) noexcept : config_(config) {}

  void set_target(Target t, TimeNs now) noexcept;
  Target target() const noexcept { return target_; }
  // Asks for a fault reset: a rising edge of bit 7 once the drive is in fault, again (up to
  // fault_reset_tries edges) while it stays there. Forgotten when the drive leaves fault, or at
  // once if it is in no fault state. Ask only once the drive's statusword has been received.
  void request_fault_reset(TimeNs now) noexcept;
  // Extra controlword bits for the mode (4..6, 8..15: halt, mode-specific); others are ignored.
  void set_mode_bits(std::uint16_t bits) noexcept { mode_bits_ = bits & controlword::mode_bits; }

  ControllerOutput update(std::uint16_t statusword, TimeNs now) noexcept;

 private:
  std::uint16_t command_for(State s) noexcept;
  bool reached(State s) const noexcept;

  ControllerConfig config_;
  Target target_ = Target::switch_on_disabled;
  std::uint16_t mode_bits_ = 0;
  bool reset_requested_ = false;
  int reset_high_cycles_ = 0;
  int resets_ = 0;
  std::uint16_t last_ = 0;
  State last_state_ = State::unknown;
  TimeNs since_ = 0;
  bool started_ = false;
};

}  // namespace saw::canopen::cia402
