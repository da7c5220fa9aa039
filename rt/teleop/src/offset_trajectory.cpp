#include "saw/teleop/offset_trajectory.hpp"

#include <ruckig/ruckig.hpp>

namespace saw::teleop {

struct OffsetTrajectory::Generator {
  explicit Generator(double cycle_seconds) : otg(cycle_seconds) {}
  ruckig::Ruckig<3> otg;
  ruckig::InputParameter<3> input;
  ruckig::OutputParameter<3> output;
};

OffsetTrajectory::~OffsetTrajectory() = default;

OffsetTrajectory::OffsetTrajectory(double cycle_seconds, OffsetLimits limits)
    : g_(std::make_unique<Generator>(cycle_seconds)) {
  set_limits(limits);
  reset(Eigen::Vector3d::Zero());
}

void OffsetTrajectory::set_limits(OffsetLimits limits) noexcept {
  g_->input.max_velocity = {limits.velocity, limits.velocity, limits.velocity};
  g_->input.max_acceleration = {limits.acceleration, limits.acceleration, limits.acceleration};
  g_->input.max_jerk = {limits.jerk, limits.jerk, limits.jerk};
}

void OffsetTrajectory::reset(const Eigen::Vector3d& offset) noexcept {
  offset_ = target_ = offset;
  for (std::size_t i = 0; i < 3; ++i) {
    const auto j = static_cast<Eigen::Index>(i);
    g_->input.current_position[i] = g_->input.target_position[i] = offset[j];
    g_->input.current_velocity[i] = g_->input.current_acceleration[i] = 0;
    g_->input.target_velocity[i] = g_->input.target_acceleration[i] = 0;
  }
  moving_ = false;
}

void OffsetTrajectory::set_target(const Eigen::Vector3d& target) noexcept {
  target_ = target;
  for (std::size_t i = 0; i < 3; ++i) g_->input.target_position[i] = target[static_cast<Eigen::Index>(i)];
  moving_ = true;
}

const Eigen::Vector3d& OffsetTrajectory::update() noexcept {
  if (!moving_) return offset_;
  const auto result = g_->otg.update(g_->input, g_->output);
  if (result == ruckig::Result::Working || result == ruckig::Result::Finished) {
    for (std::size_t i = 0; i < 3; ++i) offset_[static_cast<Eigen::Index>(i)] = g_->output.new_position[i];
    g_->output.pass_to_input(g_->input);
    if (result == ruckig::Result::Finished) moving_ = false;
  } else {
    ++errors_;
    last_error_ = static_cast<int>(result);
    reset(offset_);  // Ruckig refused the input: stay where we are, at rest
  }
  return offset_;
}

}  // namespace saw::teleop
