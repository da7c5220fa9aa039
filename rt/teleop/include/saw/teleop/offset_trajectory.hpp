// OffsetTrajectory: carries a 3-D offset to its target along a jerk-limited Ruckig trajectory.
#pragma once

#include <Eigen/Core>
#include <ruckig/ruckig.hpp>

namespace saw::teleop {

struct OffsetLimits {
  double velocity = 0.05;     // m/s
  double acceleration = 0.5;  // m/s²
  double jerk = 10.0;         // m/s³
};

// Fixed 3 DoF: Ruckig's update() then allocates nothing. The offset moves only through
// update(), so what depends on it (the displayed force) has a bounded rate of change.
class OffsetTrajectory {
 public:
  OffsetTrajectory(double cycle_seconds, OffsetLimits limits);

  // Jumps to `offset` at rest (when a jump cannot show: forces are off or the error is zero).
  void reset(const Eigen::Vector3d& offset) noexcept;
  void set_target(const Eigen::Vector3d& target) noexcept;
  const Eigen::Vector3d& target() const noexcept { return target_; }
  // One cycle along the trajectory; returns the new offset.
  const Eigen::Vector3d& update() noexcept;
  const Eigen::Vector3d& offset() const noexcept { return offset_; }
  bool moving() const noexcept { return moving_; }
  void set_limits(OffsetLimits limits) noexcept;

 private:
  ruckig::Ruckig<3> otg_;
  ruckig::InputParameter<3> input_;
  ruckig::OutputParameter<3> output_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  bool moving_ = false;
};

}  // namespace saw::teleop
