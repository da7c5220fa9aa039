#include "saw/teleop/offset_trajectory.hpp"

namespace saw::teleop {

OffsetTrajectory::OffsetTrajectory(double cycle_seconds, OffsetLimits limits) : otg_(cycle_seconds) {
  set_limits(limits);
  reset(Eigen::Vector3d::Zero());
}

void OffsetTrajectory::set_limits(OffsetLimits limits) noexcept {
  input_.max_velocity = {limits.velocity, limits.velocity, limits.velocity};
  input_.max_acceleration = {limits.acceleration, limits.acceleration, limits.acceleration};
  input_.max_jerk = {limits.jerk, limits.jerk, limits.jerk};
}

void OffsetTrajectory::reset(const Eigen::Vector3d& offset) noexcept {
  offset_ = target_ = offset;
  for (std::size_t i = 0; i < 3; ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    input_.current_position[i] = input_.target_position[i] = offset[j];
    input_.current_velocity[i] = input_.current_acceleration[i] = 0;
    input_.target_velocity[i] = input_.target_acceleration[i] = 0;
  }
  moving_ = false;
}

void OffsetTrajectory::set_target(const Eigen::Vector3d& target) noexcept {
  target_ = target;
  for (std::size_t i = 0; i < 3; ++i) input_.target_position[i] = target[static_cast<Eigen::Index>(i)];
  moving_ = true;
}

const Eigen::Vector3d& OffsetTrajectory::update() noexcept {
  if (!moving_) return offset_;
  const auto result = otg_.update(input_, output_);
  if (result == ruckig::Result::Working || result == ruckig::Result::Finished) {
    for (std::size_t i = 0; i < 3; ++i) offset_[static_cast<Eigen::Index>(i)] = output_.new_position[i];
    output_.pass_to_input(input_);
    if (result == ruckig::Result::Finished) moving_ = false;
  } else {
    reset(offset_);  // Ruckig refused the input: stay where we are, at rest
  }
  return offset_;
}

}  // namespace saw::teleop
