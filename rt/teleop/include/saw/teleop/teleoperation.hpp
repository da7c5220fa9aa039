// Teleoperation: the task between a master and a slave device that runs a control law.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string>

#include "saw/crtk.hpp"
#include "saw/description.hpp"
#include "saw/task.hpp"
#include "saw/teleop/detail/law_agreements.hpp"
#include "saw/teleop/fault_info.hpp"
#include "saw/teleop/law_registry.hpp"

namespace saw::teleop {

// The task's own settings (a law's are the law's: see law.hpp).
struct TeleopConfig {
  // s: an input older than this is a fault. Behind a DelayTask, "older" is judged on the source
  // row's time plus the delay, so a dead source still shows.
  double stale_timeout = 0.01;
  // s: how long a device that has not published yet (a remote master still coming up) is
  // waited for after start before it is a fault; 0: stale_timeout.
  double startup_timeout = 0.0;
  // s: enabled, but a device stays disabled (not busy, not paused) this long: FAULT, naming the
  // side. Meanwhile the task is busy and drives nothing.
  double device_timeout = 5.0;
  bool start_enabled = true;
  // The slave follows a pose (servo_cp: a PSM) rather than a force: the law's slave_goal, at the
  // slave's orientation when the law engaged; nothing is sent to it while the law holds (its
  // device's command watchdog then holds it). Needs a law that gives_slave_goal.
  bool slave_servo_cp = false;
  // Drive only while the master's operator_present is pressed (a console's head sensor or pedal):
  // absent, the task holds as for the clutch, and engages afresh (no step) on the return. The
  // master must then provide the operator_present event.
  bool needs_operator = false;
};

// What a run of the task comes to (its "summary" column, ColumnUse::summary): state and why,
// tracking over the ENABLED cycles, refusals, and the master sample's age at the force command.
struct TeleopSummary {
  static constexpr std::string_view type_name = "saw::teleop::TeleopSummary";
  static constexpr std::uint32_t layout_version = 2;  // 2: reason
  OperatingStateValue state = OperatingStateValue::disabled;
  FaultInfo fault{};
  std::array<char, FaultText::max + 1> reason{};  // the fault's reason in words (fault_reason())
  double tracking_rms = 0, tracking_max = 0;      // m
  std::uint64_t enabled_cycles = 0;
  std::uint64_t rejected_commands = 0, refused_sends = 0, rejected_inputs = 0, offset_errors = 0;
  double master_age_mean = 0;  // ns
  TimeNs master_age_max = 0;
  std::uint64_t master_age_late = 0;  // cycles that used a sample from an earlier cycle
};

// "ENABLED, tracking error |e_s| RMS 0.123 mm, ...": the summary's line for people.
std::string to_string(const TeleopSummary& s);

// Required interfaces "master" and "slave" (CRTK: measured_cp, measured_cv, servo_cf — optional
// on the master, which may be read-only; optional clutch event on the master (and its
// operator_present event, required with needs_operator); optional
// gripper_measured_js on the master, jaw_measured_js and jaw_servo_jp on the slave; optional
// source_time and delay, given by a DelayTask; optional operating_state). Provided interface
// "teleop": state_command; its law's settings as set_<name> commands and as read commands
// <name> (the values in force); master_force, slave_force, tracking_error, fault,
// rejected_inputs, offset_errors, and `description` (kind "teleoperation", the law, the
// components in the master and slave roles); operating_state and fault events.
//
// The task owns everything around the law: inputs are checked before use (a row that is not
// finite or stamped in the future is a failed read, the last good value is held, FAULT follows
// after stale_timeout); the state machine (enable, disable, pause, resume); the clutch; devices
// that are busy (homing: their positions mean nothing yet), paused or disabled hold the
// teleoperation as the clutch does — zero force both sides, the law held, the cycles not
// counted as ENABLED — and one still disabled after device_timeout faults it; every force is
// checked finite before it is sent; every FAULT records why (fault(), the "fault" column, and
// fault_reason() when a FaultInfo cannot say it all) and sends zero force both ways until the next
// enable. What a law reads and sends besides the devices' poses, forces and goals it declares
// (law_input.hpp, law_output.hpp: a passivity port's energies and waves); a declared input that
// must agree with a law setting (a wave port's b) is checked at start-up (a failed start) and
// every cycle, before the law uses what came with it (FAULT, config_mismatch, naming both values
// and the components).
class Teleoperation : public Task {
 public:
  Teleoperation(std::string name, TaskConfig task, TeleopConfig config, const LawSpec& law);

  void startup() override;
  void run() override;

  std::string_view law_name() const noexcept { return law_->name(); }

  // Readable from the owning thread or, through the state table, from any thread.
  OperatingStateValue operating_state() const noexcept { return state_.state; }
  const OperatingState& state() const noexcept { return state_; }
  const FaultInfo& fault() const noexcept { return fault_; }
  // The fault in more words than a FaultInfo holds, when it needs them ("" otherwise): an input
  // that no longer agrees with the law (a wave port's b) names both values and the components.
  std::string_view fault_reason() const noexcept { return fault_reason_.view(); }
  std::uint64_t rejected_commands() const noexcept { return rejected_; }
  // Input rows refused (not finite, stamped in the future).
  std::uint64_t rejected_inputs() const noexcept { return rejected_inputs_; }
  // What the law refused of itself (the collaborative law: offset trajectories Ruckig refused).
  std::uint64_t offset_errors() const noexcept { return law_->refusals(); }
  std::uint64_t refused_sends() const noexcept { return refused_sends_; }
  // |e_s| over the cycles spent ENABLED (read after stop, or from the owning thread).
  double tracking_rms() const noexcept {
    return enabled_cycles_ ? std::sqrt(tracking_sum_sq_ / static_cast<double>(enabled_cycles_)) : 0.0;
  }
  double tracking_max() const noexcept { return tracking_max_; }
  std::uint64_t enabled_cycles() const noexcept { return enabled_cycles_; }
  // End-to-end latency, master sample → the force command computed from it (ENABLED cycles):
  // mean and max in ns, and how many cycles used a sample half a period old or more (a row of
  // an earlier cycle).
  double master_age_mean() const noexcept {
    return enabled_cycles_ ? master_age_sum_ / static_cast<double>(enabled_cycles_) : 0.0;
  }
  TimeNs master_age_max() const noexcept { return master_age_max_; }
  std::uint64_t master_age_late() const noexcept { return master_age_late_; }
  const ComponentDescription& description() const noexcept { return description_; }

  // State-table columns (for tests and the recorder); the law's settings have theirs, by name.
  struct Columns {
    StateColumn<OperatingState> operating_state;
    StateColumn<Vec3> master_force, slave_force, master_error, slave_error, slave_offset;
    StateColumn<double> tracking_error;
    StateColumn<bool> ratcheting, clutched, operator_present;
    StateColumn<FaultInfo> fault;
    StateColumn<std::uint64_t> rejected_inputs, offset_errors;
    StateColumn<TeleopSummary> summary;
    StateColumn<ComponentDescription> description;
  };
  const Columns& columns() const noexcept { return columns_; }

 protected:
  // The task's deadline policy breached: FAULT in the next cycle, zero force both ways.
  void on_deadline_breach(const DeadlineBreach& b) noexcept override;

 private:
  // One device: its functions and the last good input read from it.
  struct Side {
    FaultSide side = FaultSide::none;
    FunctionRead<Pose> cp;
    FunctionRead<Twist> cv;
    FunctionWrite<Wrench> cf;
    FunctionWrite<Pose> goal;                        // a slave that follows a pose (slave_servo_cp)
    FunctionRead<JointState> grip;                   // the master's gripper, the slave's jaw (optional)
    FunctionWrite<JointState> jaw;                   // the slave's jaw goal (optional)
    FunctionRead<TimeNs> source_time, delay;         // bound when a DelayTask sits in between
    FunctionRead<OperatingState> state;              // bound when the device reports its state
    FunctionRead<ComponentDescription> description;  // a delay task's: the component behind it
    FunctionRead<std::uint64_t> trips;               // a pose-following slave's watchdog_trips
    std::uint64_t trips_seen = 0;
    bool trips_known = false;
    SideSample last{};
    Quat orientation{0, 0, 0, 1};  // of the last good input
    TimeNs time = 0;               // of the last good input: its row's, or its source row's plus the delay
    bool valid = false, not_finite = false;
    bool busy = false;    // the device said it is busy (homing): not driven meanwhile
    bool enabled = true;  // the device said it is enabled (or says nothing of its state)
    bool paused = false;
    Status status = Status::ok;  // of the last read
  };
  void require_side(Side& s, const char* iface);
  // "its input port_wave_impedance from the master ('port.arm', through 'link.arm')" (setup).
  std::string source_words(const detail::InputSlot& in);
  bool read_side(Side& s, FaultInfo& why) noexcept;
  bool read_declared(FaultInfo& why) noexcept;
  // Every cycle, after the declared inputs: a value that disagrees with the law is FAULT
  // (config_mismatch); one not read now holds the law (agreements_.unconfirmed()).
  bool check_agreements(FaultInfo& why) noexcept;
  // True once after the slave's commands stopped (its watchdog tripped): it holds where it is.
  bool slave_held() noexcept;
  // Fills fault_reason_ for a fault a FaultInfo cannot say all of (clears it otherwise).
  void explain(const FaultInfo& why) noexcept;
  // True while enabled but a device cannot be driven (busy, paused, disabled): busy, and FAULT
  // once a disabled device has kept it waiting device_timeout.
  bool waiting_for_devices() noexcept;
  Status read_time(Side& s, TimeNs row_time, TimeNs& time) noexcept;
  void handle_state_command(StateCommand c) noexcept;
  void set_operating_state(OperatingStateValue s) noexcept;
  void raise_fault(FaultInfo why) noexcept;
  void on_input_failure(const FaultInfo& why) noexcept;
  // The slave's goal (slave_servo_cp) instead of its force, and its jaw, when `law` is given.
  void send_forces(const Eigen::Vector3d& f_master, const Eigen::Vector3d& f_slave,
                   const LawCommand* law = nullptr) noexcept;
  void read_grip(Side& s) noexcept;
  void note_refusals() noexcept;
  void account(const LawCommand& law) noexcept;
  void cycle_body() noexcept;
  void refresh_summary() noexcept;

  TeleopConfig config_;
  std::unique_ptr<LawModel> law_;
  InputSet inputs_;    // what the law declared it reads besides the sides
  OutputSet outputs_;  // what the law declared it sends besides the forces and goals
  const detail::InputSlot* stale_input_ = nullptr;  // the declared input the last FAULT was for
  bool clutched_ = false, ratcheting_ = false;
  bool operator_present_ = false;  // the master's operator_present event, last pressed or released
  bool deadline_breached_ = false;
  DeadlineBreach deadline_breach_{};
  Quat held_orientation_{0, 0, 0, 1};  // the slave's at engagement (slave_servo_cp)
  bool engage_pending_ = true;         // the next engaged cycle (re-)engages the law: reset, not step
  bool inputs_seen_ = false;           // a producer that has not published yet is not a fault, for a while
  TimeNs start_time_ = -1;
  TimeNs waiting_since_ = -1;  // enabled, a device not: since when
  FaultInfo fault_{};
  FaultText fault_reason_{};
  detail::LawAgreements agreements_;  // declared inputs that must equal a law setting
  const detail::LawAgreements::Agreement* disagreed_ = nullptr;  // the last config_mismatch's
  std::uint64_t rejected_ = 0, refused_sends_ = 0, rejected_inputs_ = 0, offset_errors_ = 0;
  double tracking_sum_sq_ = 0, tracking_max_ = 0;
  std::uint64_t enabled_cycles_ = 0;
  TimeNs master_age_ = 0, master_age_max_ = 0;
  double master_age_sum_ = 0;
  std::uint64_t master_age_late_ = 0;

  // State-table sources.
  OperatingState state_{};
  Vec3 master_force_{}, slave_force_{}, master_error_{}, slave_error_{}, slave_offset_value_{};
  double tracking_error_ = 0;
  TeleopSummary summary_{};
  ComponentDescription description_{};
  Columns columns_;

  // Required: master and slave.
  Side master_, slave_;
  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<FaultInfo>* fault_event_ = nullptr;
};

}  // namespace saw::teleop
