// DelayTask: re-publishes a device's CRTK state as it was `delay` ago, to simulate a network.
#pragma once

#include "saw/crtk_arm.hpp"
#include "saw/task.hpp"

namespace saw::teleop {

// What a DelayTask adds to the arm interface it re-publishes; Teleoperation reads
// them, when present, to judge staleness on the source.
namespace delayed_arm {
inline constexpr crtk::Read<TimeNs> source_time{"source_time"};  // of the source row shown
inline constexpr crtk::Read<TimeNs> delay{"delay"};              // how late it is meant to be
}  // namespace delayed_arm

// Required "source" (a device's arm interface), provided "arm" with the same CRTK names.
// Positions and velocities come out `delay` late, read from this task's own state-table
// history; force commands and button events pass through (one cycle later). The rows are this
// task's, stamped with its cycle: "source_time" says when the source wrote the value shown
// (it stops advancing when the source dies) and "delay" how late it is meant to be, so that a
// consumer can judge staleness on the source (Teleoperation does).
class DelayTask : public Task {
 public:
  DelayTask(std::string name, TaskConfig task, double delay_seconds);

  void run() override;
  double delay() const noexcept { return static_cast<double>(delay_) * 1e-9; }

 private:
  TimeNs delay_;
  Pose source_cp_{}, measured_cp_{};
  Twist source_cv_{}, measured_cv_{};
  TimeNs source_row_time_ = 0, source_time_ = 0;  // of the source row read now; of the one shown
  StateColumn<Pose> source_cp_column_;
  StateColumn<Twist> source_cv_column_;
  StateColumn<TimeNs> source_row_time_column_;
  bool have_output_ = false;
  FunctionRead<Pose> read_cp_;
  FunctionRead<Twist> read_cv_;
  FunctionWrite<Wrench> write_cf_;
  EventWrite<ButtonEvent>* clutch_ = nullptr;
  EventWrite<ButtonEvent>* operator_present_ = nullptr;
};

}  // namespace saw::teleop
