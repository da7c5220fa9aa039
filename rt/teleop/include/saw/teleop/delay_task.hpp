// DelayTask: re-publishes a device's CRTK state as it was `delay` ago, to simulate a network.
#pragma once

#include "saw/crtk.hpp"
#include "saw/task.hpp"

namespace saw::teleop {

// Required "source" (a device's arm interface), provided "arm" with the same CRTK names.
// Positions and velocities come out `delay` late, read from this task's own state-table
// history; force commands and button events pass through (one cycle later).
class DelayTask : public Task {
 public:
  DelayTask(std::string name, TaskConfig task, double delay_seconds);

  void run() override;
  double delay() const noexcept { return static_cast<double>(delay_) * 1e-9; }

 private:
  TimeNs delay_;
  Pose source_cp_{}, measured_cp_{};
  Twist source_cv_{}, measured_cv_{};
  StateColumn<Pose> source_cp_column_;
  StateColumn<Twist> source_cv_column_;
  bool have_output_ = false;
  FunctionRead<Pose> read_cp_;
  FunctionRead<Twist> read_cv_;
  FunctionWrite<Wrench> write_cf_;
  EventWrite<ButtonEvent>* clutch_ = nullptr;
  EventWrite<ButtonEvent>* operator_present_ = nullptr;
};

}  // namespace saw::teleop
