// OffsetTrajectory: carries a 3-D offset to its target along a jerk-limited Ruckig trajectory.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <string_view>
#include <tuple>

namespace saw::teleop {

struct OffsetLimits {
  // Crosses processes as the collaborative law's set_offset_limits and its read-back `offset_limits`.
  static constexpr std::string_view type_name = "saw::teleop::OffsetLimits";
  static constexpr std::uint32_t layout_version = 1;
  double velocity = 0.05;     // m/s
  double acceleration = 0.5;  // m/s²
  double jerk = 10.0;         // m/s³
  static constexpr auto fields =
      std::tuple{&OffsetLimits::velocity, &OffsetLimits::acceleration, &OffsetLimits::jerk};
  // Each limit within [smallest, its max]: beyond them Ruckig's plans degenerate or the offset
  // jumps. Checked where a value enters from another process (saw::check_value) and by the task.
  static constexpr double smallest = 1e-6, max_velocity = 10, max_acceleration = 1e3, max_jerk = 1e5;
  static constexpr std::string_view range = "each ≥ 1e-6; velocity ≤ 10, acceleration ≤ 1e3, jerk ≤ 1e5";
  static bool valid(const OffsetLimits& v) noexcept {
    const auto in = [](double x, double hi) { return x >= smallest && x <= hi; };  // false for NaN
    return in(v.velocity, max_velocity) && in(v.acceleration, max_acceleration) && in(v.jerk, max_jerk);
  }
};

// Fixed 3 DoF: Ruckig's update() then allocates nothing. The offset moves only through
// update(), so what depends on it (the displayed force) has a bounded rate of change.
class OffsetTrajectory {
 public:
  OffsetTrajectory(double cycle_seconds, OffsetLimits limits);
  ~OffsetTrajectory();

  // Jumps to `offset` at rest (when a jump cannot show: forces are off or the error is zero).
  void reset(const Eigen::Vector3d& offset) noexcept;
  void set_target(const Eigen::Vector3d& target) noexcept;
  const Eigen::Vector3d& target() const noexcept { return target_; }
  // One cycle along the trajectory; returns the new offset.
  const Eigen::Vector3d& update() noexcept;
  const Eigen::Vector3d& offset() const noexcept { return offset_; }
  bool moving() const noexcept { return moving_; }
  void set_limits(OffsetLimits limits) noexcept;
  // Cycles on which Ruckig refused the input (the offset then stays where it is, at rest), and
  // the last refusal's code (ruckig::Result, negative).
  std::uint64_t errors() const noexcept { return errors_; }
  int last_error() const noexcept { return last_error_; }

 private:
  // Ruckig's generator and its parameters, allocated once here: Ruckig stays out of the
  // installed headers (it is built from its sdist into this library, not installed).
  struct Generator;
  std::unique_ptr<Generator> g_;
  Eigen::Vector3d offset_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  bool moving_ = false;
  std::uint64_t errors_ = 0;
  int last_error_ = 0;
};

}  // namespace saw::teleop
