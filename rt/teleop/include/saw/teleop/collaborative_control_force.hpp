// CollaborativeControlForce: the paper's teleoperation task between a master and a slave device.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "saw/crtk.hpp"
#include "saw/task.hpp"
#include "saw/teleop/offset_trajectory.hpp"
#include "saw/teleop/teleop_law.hpp"

namespace saw::teleop {

// The local model predicts only the inputs that arrive late: a side's horizon is the delay of
// the link its positions come over (0 for a device beside this task).
struct Prediction {
  static constexpr std::uint32_t layout_version = 1;
  bool enabled = false;
  double master_horizon = 0.0;  // s
  double slave_horizon = 0.0;   // s
};

struct TeleopConfig {
  Scale scale;
  Gains gains;
  ForceLimits limits;
  bool ratchet = true;
  OffsetLimits offset_limits;
  Prediction prediction;
  double stale_timeout = 0.01;  // s: an input older than this is a fault
  // s: how long a device that has not published yet (a remote master still coming up) is
  // waited for after start before it is a fault; 0: stale_timeout.
  double startup_timeout = 0.0;
  // Aligned mode: after enabling, the slave offset travels (jerk-limited) from the value that
  // cancels the error to `slave_offset`, pulling the slave smoothly into the configured pose.
  bool align = false;
  Vec3 slave_offset{};
  bool start_enabled = true;
};

enum class FaultReason : std::uint8_t { none, master_stale, slave_stale, master_missing, slave_missing };

constexpr std::string_view to_string(FaultReason r) {
  switch (r) {
    case FaultReason::none:
      return "none";
    case FaultReason::master_stale:
      return "master input stale";
    case FaultReason::slave_stale:
      return "slave input stale";
    case FaultReason::master_missing:
      return "master input missing";
    case FaultReason::slave_missing:
      return "slave input missing";
  }
  return "?";
}

// Required interfaces "master" and "slave" (CRTK: measured_cp, measured_cv, servo_cf; optional
// clutch event on the master). Provided interface "teleop": state_command, set_scale,
// set_gains, set_force_limits, set_prediction, set_slave_offset, and its state as read commands.
class CollaborativeControlForce : public Task {
 public:
  CollaborativeControlForce(std::string name, TaskConfig task, TeleopConfig config);

  void run() override;

  // Readable from the owning thread or, through the state table, from any thread.
  OperatingStateValue operating_state() const noexcept { return state_.state; }
  FaultReason fault_reason() const noexcept { return fault_; }
  std::uint64_t rejected_commands() const noexcept { return rejected_; }
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
  };
  const Columns& columns() const noexcept { return columns_; }

 private:
  struct Input {
    Eigen::Vector3d position, velocity;
  };
  struct LastInput {
    Input input{};
    TimeNs time = 0;
    bool valid = false;
  };
  bool read_inputs(Input& master, Input& slave) noexcept;
  void handle_state_command(StateCommand c) noexcept;
  void set_operating_state(OperatingStateValue s) noexcept;
  void send_forces(const Eigen::Vector3d& f_master, const Eigen::Vector3d& f_slave) noexcept;
  Eigen::Vector3d predict(const Input& in, double horizon) const noexcept;
  void snap_offsets(const Input& master, const Input& slave) noexcept;

  TeleopConfig config_;
  OffsetTrajectory slave_offset_;
  Eigen::Vector3d master_offset_ = Eigen::Vector3d::Zero();
  bool clutched_ = false, ratcheting_ = false, snap_pending_ = true;
  bool rescale_pending_ = false;
  bool inputs_seen_ = false;  // a producer that has not published yet is not a fault, for a while
  TimeNs start_time_ = -1;
  Scale previous_scale_;
  FaultReason fault_ = FaultReason::none;
  LastInput last_master_, last_slave_;
  std::uint64_t rejected_ = 0, refused_sends_ = 0;
  double tracking_sum_sq_ = 0, tracking_max_ = 0;
  std::uint64_t enabled_cycles_ = 0;
  TimeNs master_age_ = 0, master_age_max_ = 0;
  double master_age_sum_ = 0;
  std::uint64_t master_age_late_ = 0;

  // State-table sources.
  OperatingState state_{};
  Vec3 master_force_{}, slave_force_{}, master_error_{}, slave_error_{}, slave_offset_value_{};
  double tracking_error_ = 0;
  Columns columns_;

  // Required: master and slave.
  FunctionRead<Pose> master_cp_, slave_cp_;
  FunctionRead<Twist> master_cv_, slave_cv_;
  FunctionWrite<Wrench> master_cf_, slave_cf_;
  EventWrite<OperatingState>* state_event_ = nullptr;
};

}  // namespace saw::teleop
