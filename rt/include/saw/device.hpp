// Device: the base of every device driver; it owns the device contract, a driver only its hardware.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "saw/command_watchdog.hpp"
#include "saw/crtk_arm.hpp"
#include "saw/fault.hpp"
#include "saw/task.hpp"

namespace saw {

// What "safe" means for a device's hardware: the output it takes when commands stop, on a fault,
// `disable`, a stop, process exit and a failed start.
enum class SafeState : std::uint8_t {
  zero_force,      // a haptic device: no force on the operator's hand
  hold,            // a position-controlled arm: stay where it is
  drive_disabled,  // a drive: power stage off (a CiA 402 drive: quick stop, then disabled)
};
constexpr std::size_t enum_count(SafeState) { return 3; }
constexpr std::string_view enum_type_name(SafeState) { return "saw::SafeState"; }
std::string_view to_string(SafeState s) noexcept;

// Which of the base's own checks raised a fault; `driver` for one its hardware calls reported
// (or threw). Carried typed in DeviceStatus so that a driver tells them apart without reading text.
enum class FaultOrigin : std::uint8_t {
  none,
  driver,           // read(), write(), enable() or home() failed or threw
  enable_timeout,   // enable() still pending after enable_timeout
  home_timeout,     // home() still pending after home_timeout
  command_timeout,  // no servo command within command_timeout (fault_on_command_timeout)
  deadline_missed,  // the device's task missed its deadline
};
constexpr std::size_t enum_count(FaultOrigin) { return 6; }
constexpr std::string_view enum_type_name(FaultOrigin) { return "saw::FaultOrigin"; }

// Why the base put the device in its safe state (the driver may care: a drive quick-stops on a
// fault but disables voltage on `disable`).
enum class SafeReason : std::uint8_t { disable, fault, stop, start_failed };
const char* to_string(SafeReason r) noexcept;  // a literal

// The servo command kinds of CRTK a device may take.
enum class ServoMode : std::uint8_t {
  none,  // no command this cycle: the device's safe output (zero force, hold, zero velocity)
  cf,    // servo_cf: a Cartesian wrench
  jp,    // servo_jp: joint positions
  jv,    // servo_jv: joint velocities
  jf,    // servo_jf: joint efforts
  cp,    // servo_cp: a Cartesian pose
};
const char* to_string(ServoMode m) noexcept;  // "servo_cf", ...

// One command as the driver receives it: already checked (finite, within the declared limits,
// the device's mode), or `none`.
struct Setpoint {
  ServoMode mode = ServoMode::none;
  Wrench wrench{};                                      // cf
  std::array<double, JointState::max_joints> joints{};  // jp, jv, jf: SI units
  Pose pose{};                                          // cp: a unit quaternion, in the workspace
};

// What a hardware call came to. `why` is a literal (it is kept and logged from RT code);
// `source` names the part (a USB port, a node, a joint) and must outlive the device.
struct Outcome {
  enum class Kind : std::uint8_t { done, pending, failed };
  Kind kind = Kind::done;
  FaultCode code = FaultCode::none;
  std::uint32_t detail = 0;
  const char* why = "";
  std::string_view source{};
  TimeNs age = 0;  // how old the last good input was (a stale input), or 0

  static constexpr Outcome done() noexcept { return {}; }
  static constexpr Outcome pending() noexcept { return {Kind::pending}; }
  static constexpr Outcome failed(FaultCode code, const char* why, std::string_view source = {},
                                  std::uint32_t detail = 0, TimeNs age = 0) noexcept {
    return {Kind::failed, code, detail, why, source, age};
  }
  constexpr bool is_done() const noexcept { return kind == Kind::done; }
  constexpr bool is_failed() const noexcept { return kind == Kind::failed; }
};

// One joint's declared limits (SI: rad or m). A command beyond them is refused before the driver
// sees it.
struct JointLimits {
  std::string name;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  double max_velocity = std::numeric_limits<double>::infinity();  // servo_jv; servo_jp's step rate
  double max_effort = std::numeric_limits<double>::infinity();    // servo_jf
};

// What a deployment sets of any device's contract: the device base's own keys, read once for
// every driver by deploy::parse_device_settings (one range per key). A driver's config holds one
// (`contract`), with its hardware's defaults.
struct DeviceSettings {
  double max_force = 0;  // servo_cf: |force| above this (N) is refused; 0: not bounded here
  // With no fresh servo command for this long, the device takes its safe output (zero force,
  // hold) and says so; with fault_on_command_timeout it also goes to FAULT. 0: 3 periods.
  TimeNs command_timeout = 0;
  bool fault_on_command_timeout = false;
  bool start_enabled = true;              // enable in the first cycle (a simulator; hardware waits)
  TimeNs enable_timeout = 1'000'000'000;  // enable() pending longer: FAULT
  TimeNs home_timeout = 0;                // home() pending longer: FAULT; 0: no limit here
  // servo_cp: a pose inside the workspace box, moving from the last accepted pose (or the
  // measured one: first, and after commands stopped) no faster than these (m/s, rad/s).
  double max_linear_speed = std::numeric_limits<double>::infinity();
  double max_angular_speed = std::numeric_limits<double>::infinity();
  Vec3 workspace_min{-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                     -std::numeric_limits<double>::infinity()};
  Vec3 workspace_max{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                     std::numeric_limits<double>::infinity()};
};

// The contract the base runs: the deployment's settings and what the driver's hardware is.
struct DeviceConfig : DeviceSettings {
  std::string interface_name = "arm";  // the provided CRTK interface
  SafeState safe_state = SafeState::zero_force;
  bool cartesian = true;            // measured_cp, measured_cv
  bool servo_cf = true;             // takes servo_cf (needs cartesian)
  std::vector<JointLimits> joints;  // measured_js's joints, 1..8
  bool servo_jp = false, servo_jv = false, servo_jf = false;
  bool servo_cp = false;  // takes servo_cp (needs cartesian), checked by the settings' box and speeds

  DeviceSettings& settings() noexcept { return *this; }
};

// A driver's configuration, checked (and completed) once: its public constructor delegates with
// it, so that the base's contract and the driver's own copy come from one check.
// Explicit, without a default: `{}` for a config still means the driver's own config type.
template <class Config>
struct Checked {
  explicit Checked(Config v) : value(std::move(v)) {}
  Config value;
};

// Commands refused before they reached the driver, by why.
struct RefusedCommands {
  static constexpr std::string_view type_name = "saw::RefusedCommands";
  static constexpr std::uint32_t layout_version = 1;
  std::uint64_t not_finite = 0;  // NaN or infinity anywhere in it
  std::uint64_t over_limit = 0;  // a force, position, step, velocity or effort beyond its limit
  std::uint64_t wrong_mode = 0;  // a servo kind the device does not take in its mode
  std::uint64_t wrong_size = 0;  // a joint state whose size is not the number of joints
  static constexpr auto fields = std::tuple{&RefusedCommands::not_finite, &RefusedCommands::over_limit,
                                            &RefusedCommands::wrong_mode, &RefusedCommands::wrong_size};
  std::uint64_t total() const noexcept { return not_finite + over_limit + wrong_mode + wrong_size; }
};

// The contract's state and counters: the "device" column (a summary, printed when a run ends).
struct DeviceStatus {
  static constexpr std::string_view type_name = "saw::DeviceStatus";
  static constexpr std::uint32_t layout_version = 2;  // 2: origin
  static constexpr std::size_t max_reason = 63;
  OperatingStateValue state = OperatingStateValue::disabled;
  SafeState safe_state = SafeState::zero_force;
  bool safe_output = true;  // this cycle's output was the safe one (no command reached the hardware)
  std::uint32_t faults = 0;
  std::uint64_t watchdog_trips = 0;
  std::uint64_t safe_entries = 0;  // times the safe state was entered (disable, fault, stop)
  TimeNs command_timeout = 0;
  RefusedCommands refused{};
  FaultInfo fault{};                          // the last fault (kept after recovery)
  std::array<char, max_reason + 1> reason{};  // the last fault's reason, as the driver said it
  FaultOrigin origin = FaultOrigin::none;     // the last fault's: which check raised it
  static constexpr auto fields =
      std::tuple{&DeviceStatus::state,           &DeviceStatus::safe_state,     &DeviceStatus::safe_output,
                 &DeviceStatus::faults,          &DeviceStatus::watchdog_trips, &DeviceStatus::safe_entries,
                 &DeviceStatus::command_timeout, &DeviceStatus::refused,        &DeviceStatus::fault,
                 &DeviceStatus::reason,          &DeviceStatus::origin};
  std::string_view reason_text() const noexcept;
};

// A device as a periodic task. The base provides the CRTK interface (measured_cp/cv/js,
// operating_state, fault, command_timeout, watchdog_trips reads; servo_cf/cp/jp/jv/jf as declared,
// state_command writes; operating_state, fault, clutch, operator_present events), runs the
// operating-state machine (enable, disable, pause, resume, home), checks every command before
// the driver sees it, runs the command watchdog, and drives the safe state on watchdog, fault,
// disable, stop and a failed start. A driver implements the hardware calls below, nothing of
// the contract; the base calls them in this order each cycle: read, [enable], [home], write.
class Device : public Task {
 public:
  Device(std::string name, TaskConfig task, DeviceConfig config);
  ~Device() override;

  void startup() final;
  void cleanup() final;
  void run() final;

  const DeviceConfig& contract() const noexcept { return config_; }
  const OperatingState& operating_state() const noexcept { return state_; }
  const FaultInfo& fault() const noexcept { return fault_; }
  const DeviceStatus& device_status() const noexcept { return status_; }
  std::uint64_t watchdog_trips() const noexcept { return watchdog_.trips(); }
  const CommandWatchdog& watchdog() const noexcept { return watchdog_; }
  struct ContractColumns {
    StateColumn<Pose> measured_cp;  // cartesian devices
    StateColumn<Twist> measured_cv;
    StateColumn<JointState> measured_js;  // devices with joints
    StateColumn<OperatingState> operating_state;
    StateColumn<FaultInfo> fault;
    StateColumn<DeviceStatus> status;
  };
  const ContractColumns& contract_columns() const noexcept { return columns_; }
  bool homing() const noexcept { return homing_; }
  bool enabling() const noexcept { return enabling_; }
  // The operating state is enabled, nothing is under way and a command may reach the hardware.
  bool following() const noexcept {
    return state_.state == OperatingStateValue::enabled && !enabling_ && !homing_;
  }

 protected:
  // ---- the hardware interface: what a driver implements ------------------------------------
  // Not RT, before the first cycle: open and configure the hardware. Throw (std::exception)
  // saying why it cannot: the base puts the device in its safe state, closes it and the start
  // fails with that message.
  virtual void open() {}
  // Not RT, last: release the hardware (the safe state was entered just before). Never throws.
  virtual void close() noexcept {}
  // RT, first in every cycle: take this cycle's inputs into measured(); failed: FAULT.
  virtual Outcome read() = 0;
  // RT, last in every cycle: apply the checked command, or the safe output for ServoMode::none.
  virtual Outcome write(const Setpoint& s) = 0;
  // RT, each cycle after `enable` until done (a drive walks to operation enabled; faults reset).
  virtual Outcome enable() { return Outcome::done(); }
  // RT, each cycle while homing until done.
  virtual Outcome home() { return Outcome::done(); }
  // RT or not: enter the safe state now (idempotent). The next write()s carry ServoMode::none.
  virtual void enter_safe_state(SafeReason why) = 0;
  // RT, in the command's handler, after the base's checks: turn the command into what the
  // hardware takes (servo_cf into joint efforts) or refuse it (false: counted as over the limit).
  virtual bool admit(Setpoint&) { return true; }
  // Whether the device takes this servo kind now (its mode); refused as wrong_mode otherwise.
  virtual bool accepts(ServoMode) const noexcept { return true; }
  // The task's deadline policy breached: FAULT in the next cycle, through the safe state.
  void on_deadline_breach(const DeadlineBreach& b) noexcept override;

  // ---- what a driver uses -----------------------------------------------------------------
  struct Measured {
    Pose cp{};
    Twist cv{};
    JointState js{};  // names and size are the declared joints'
  };
  Measured& measured() noexcept { return measured_; }
  const Measured& measured() const noexcept { return measured_; }
  // A button of the device: the clutch and operator_present events on each change.
  enum class Button : std::uint8_t { clutch, operator_present };
  void button(Button b, bool pressed) noexcept;
  // From open() or a cycle: start homing (busy until home() is done).
  void start_homing() noexcept;
  // From a cycle: the hardware lost its reference (a Falcon no longer reports its arms homed):
  // is_homed is false until the next homing is done; said as an operating_state event.
  void lose_homing() noexcept;
  // From a command handler: the client ended its servo commands with one the hardware carries
  // out itself (the dVRK's move_cp): the last servo command is not written again, and the silence
  // after it is no watchdog trip, until the next servo command.
  void end_servo() noexcept;
  // From a cycle: the hardware carries out a move of the client's (the dVRK's trajectory after a
  // move_cp): busy while it does, as CRTK's is_busy says, so that a client waits for it; an
  // operating_state event on each change. A fault or a disable ends it.
  void set_moving(bool moving) noexcept;
  // From a cycle: a fault the driver sees outside its hardware calls.
  void raise(const Outcome& why, FaultOrigin origin = FaultOrigin::driver) noexcept;
  // In FAULT: what is known now about the same fault replaces what was said (a silent node seen
  // first as stale feedback, then as a lost heartbeat); said again as a fault event.
  void update_fault(const Outcome& why) noexcept;
  // The provided CRTK interface ("arm", or the name the driver gave it: "io"), for a driver's own
  // reads (after the base's constructor).
  ProvidedInterface& crtk_interface() noexcept { return *arm_; }

 private:
  void provide_interfaces();
  void servo_cf(const Wrench& w) noexcept;
  void servo_joints(const JointState& js, ServoMode mode) noexcept;
  void servo_cp(const Pose& p) noexcept;
  void refuse(std::uint64_t& counter) noexcept;
  void state_command(StateCommand c) noexcept;
  void set_state(OperatingStateValue s) noexcept;
  void safe(SafeReason why) noexcept;
  void describe(const Outcome& why) noexcept;
  void begin_enable(TimeNs t) noexcept;
  void step_enable(TimeNs t) noexcept;
  void step_home(TimeNs t) noexcept;
  void watch_commands(TimeNs t) noexcept;
  void publish() noexcept;
  template <class F>
  Outcome guarded(F&& call) noexcept;

  DeviceConfig config_;
  ContractColumns columns_;
  ProvidedInterface* arm_ = nullptr;
  CommandWatchdog watchdog_;
  Setpoint command_{};  // the last accepted command (none after a refusal, a timeout, a disable)
  Measured measured_{};
  std::array<double, JointState::max_joints> last_jp_{};
  TimeNs last_jp_time_ = 0;
  bool has_jp_ = false;
  Pose last_cp_{};
  TimeNs last_cp_time_ = 0;
  bool has_cp_ = false;
  OperatingState state_{};
  FaultInfo fault_{};
  DeviceStatus status_{};
  bool enable_requested_ = false, enabling_ = false, homing_ = false, moving_ = false;
  // CRTK's is_busy, the one rule: an enable, a homing or a move of the hardware's under way.
  bool busy() const noexcept { return enabling_ || homing_ || moving_; }
  TimeNs enable_start_ = 0, home_start_ = -1, t0_ = -1;
  std::array<bool, 2> buttons_{};
  bool deadline_breached_ = false;
  DeadlineBreach deadline_breach_{};
  std::array<char, DeviceStatus::max_reason + 1> threw_{};  // what a throwing driver said
  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<FaultInfo>* fault_event_ = nullptr;
  EventWrite<ButtonEvent>* clutch_event_ = nullptr;
  EventWrite<ButtonEvent>* operator_event_ = nullptr;
};

// A driver's throw, caught: RT code must not let it out, and the device goes to FAULT saying it.
template <class F>
inline Outcome Device::guarded(F&& call) noexcept {
  try {
    return call();
  } catch (const std::exception& e) {
    // Copied: the exception dies here, the reason is kept and logged later.
    std::strncpy(threw_.data(), e.what(), threw_.size() - 1);
    return Outcome::failed(FaultCode::device_error, threw_.data(), "driver");
  } catch (...) {
    return Outcome::failed(FaultCode::device_error, "the driver threw something unknown", "driver");
  }
}

}  // namespace saw
