// CollaborativeControlForce: the paper's teleoperation task between a master and a slave device.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "saw/crtk.hpp"
#include "saw/task.hpp"
#include "saw/teleop/fault_info.hpp"
#include "saw/teleop/offset_trajectory.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

// The local model predicts only the inputs that arrive late: a side's horizon is the delay of
// the link its positions come over (0 for a device beside this task).
struct Prediction {
  static constexpr std::string_view type_name = "saw::teleop::Prediction";
  static constexpr std::uint32_t layout_version = 1;
  bool enabled = false;
  double master_horizon = 0.0;  // s
  double slave_horizon = 0.0;   // s
};
// Crosses processes byte for byte (set_prediction).
static_assert(sizeof(Prediction) == 24 && offsetof(Prediction, master_horizon) == 8 &&
              offsetof(Prediction, slave_horizon) == 16);

struct TeleopConfig {
  Scale scale;
  Gains gains;
  ForceLimits limits;
  bool ratchet = true;
  OffsetLimits offset_limits;
  Prediction prediction;
  // s: an input older than this is a fault. Behind a DelayTask, "older" is judged on the source
  // row's time plus the delay, so a dead source still shows.
  double stale_timeout = 0.01;
  // s: how long a device that has not published yet (a remote master still coming up) is
  // waited for after start before it is a fault; 0: stale_timeout.
  double startup_timeout = 0.0;
  // s: enabled, but a device stays disabled (not busy, not paused) this long: FAULT, naming the
  // side. Meanwhile the task is busy and drives nothing.
  double device_timeout = 5.0;
  // Aligned mode: after enabling, the slave offset travels (jerk-limited) from the value that
  // cancels the error to `slave_offset`, pulling the slave smoothly into the configured pose.
  bool align = false;
  Vec3 slave_offset{};
  bool start_enabled = true;
};

// What a run of the task comes to (its "summary" column, ColumnUse::summary): state and why,
// tracking over the ENABLED cycles, refusals, and the master sample's age at the force command.
struct TeleopSummary {
  static constexpr std::string_view type_name = "saw::teleop::TeleopSummary";
  static constexpr std::uint32_t layout_version = 1;
  OperatingStateValue state = OperatingStateValue::disabled;
  FaultInfo fault{};
  double tracking_rms = 0, tracking_max = 0;  // m
  std::uint64_t enabled_cycles = 0;
  std::uint64_t rejected_commands = 0, refused_sends = 0, rejected_inputs = 0, offset_errors = 0;
  double master_age_mean = 0;  // ns
  TimeNs master_age_max = 0;
  std::uint64_t master_age_late = 0;  // cycles that used a sample from an earlier cycle
};

// "ENABLED, tracking error |e_s| RMS 0.123 mm, ...": the summary's line for people.
std::string to_string(const TeleopSummary& s);

// Required interfaces "master" and "slave" (CRTK: measured_cp, measured_cv, servo_cf; optional
// clutch event on the master; optional source_time and delay, given by a DelayTask). Provided
// interface "teleop": state_command, set_scale, set_gains, set_force_limits, set_prediction,
// set_slave_offset; its state as read commands; operating_state and fault events.
// Inputs are checked before use: a row that is not finite (or stamped in the future) is a failed
// read, the last good value is held, and FAULT follows after stale_timeout. Every force is
// checked finite before it is sent; every FAULT records why (fault(), the "fault" column).
// A device whose operating_state says busy (homing: its positions mean nothing yet) holds the
// teleoperation as the clutch does: zero force on both sides, the offset kept cancelling, and
// the cycles are not counted as ENABLED (nor in the tracking figures).
class CollaborativeControlForce : public Task {
 public:
  CollaborativeControlForce(std::string name, TaskConfig task, TeleopConfig config);

  void run() override;

  // Readable from the owning thread or, through the state table, from any thread.
  OperatingStateValue operating_state() const noexcept { return state_.state; }
  const OperatingState& state() const noexcept { return state_; }
  const FaultInfo& fault() const noexcept { return fault_; }
  std::uint64_t rejected_commands() const noexcept { return rejected_; }
  // Input rows refused (not finite, stamped in the future) and Ruckig refusals of the offset.
  std::uint64_t rejected_inputs() const noexcept { return rejected_inputs_; }
  std::uint64_t offset_errors() const noexcept { return slave_offset_.errors(); }
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

  // State-table columns (for tests and the recorder).
  struct Columns {
    StateColumn<OperatingState> operating_state;
    StateColumn<Vec3> master_force, slave_force, master_error, slave_error, slave_offset;
    StateColumn<double> tracking_error;
    StateColumn<bool> ratcheting, clutched;
    StateColumn<FaultInfo> fault;
    StateColumn<std::uint64_t> rejected_inputs, offset_errors;
    StateColumn<TeleopSummary> summary;
  };
  const Columns& columns() const noexcept { return columns_; }

 private:
  struct Input {
    Eigen::Vector3d position, velocity;
  };
  // One device: its functions and the last good input read from it.
  struct Side {
    FaultSide side = FaultSide::none;
    FunctionRead<Pose> cp;
    FunctionRead<Twist> cv;
    FunctionWrite<Wrench> cf;
    FunctionRead<TimeNs> source_time, delay;  // bound when a DelayTask sits in between
    FunctionRead<OperatingState> state;       // bound when the device reports its state
    Input last{};
    TimeNs time = 0;  // of the last good input: its row's, or its source row's plus the delay
    bool valid = false, not_finite = false;
    bool busy = false;    // the device said it is busy (homing): not driven meanwhile
    bool enabled = true;  // the device said it is enabled (or says nothing of its state)
    bool paused = false;
    Status status = Status::ok;  // of the last read
  };
  // What the offset is expressed in: a change re-expresses it so that e_s does not jump.
  struct LawSettings {
    Scale scale;
    Prediction prediction;
  };
  void add_settings(ProvidedInterface& p);
  void require_side(Side& s, const char* iface);
  bool read_side(Side& s, Input& out, FaultInfo& why) noexcept;
  // True while enabled but a device cannot be driven (busy, paused, disabled): busy, and FAULT
  // once a disabled device has kept it waiting device_timeout.
  bool waiting_for_devices() noexcept;
  Status read_time(Side& s, TimeNs row_time, TimeNs& time) noexcept;
  void handle_state_command(StateCommand c) noexcept;
  void set_operating_state(OperatingStateValue s) noexcept;
  void raise_fault(FaultInfo why) noexcept;
  void on_input_failure(const FaultInfo& why) noexcept;
  void send_forces(const Eigen::Vector3d& f_master, const Eigen::Vector3d& f_slave) noexcept;
  Eigen::Vector3d predict(const Input& in, double horizon, const Prediction& pr) const noexcept;
  void snap_offsets(const Input& master, const Input& slave) noexcept;
  void reexpress_offset(const Input& master, const Input& slave) noexcept;
  void step_offset() noexcept;
  void ratchet(const Eigen::Vector3d& p_m, const Eigen::Vector3d& p_s) noexcept;
  void account(const LawOutput& law) noexcept;
  void cycle_body() noexcept;
  void refresh_summary() noexcept;

  TeleopConfig config_;
  OffsetTrajectory slave_offset_;
  Eigen::Vector3d master_offset_ = Eigen::Vector3d::Zero();
  bool clutched_ = false, ratcheting_ = false, snap_pending_ = true;
  bool reexpress_pending_ = false;
  bool inputs_seen_ = false;  // a producer that has not published yet is not a fault, for a while
  TimeNs start_time_ = -1;
  TimeNs waiting_since_ = -1;  // enabled, a device not: since when
  LawSettings previous_;
  FaultInfo fault_{};
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
  Columns columns_;

  // Required: master and slave.
  Side master_, slave_;
  EventWrite<OperatingState>* state_event_ = nullptr;
  EventWrite<FaultInfo>* fault_event_ = nullptr;
};

}  // namespace saw::teleop
