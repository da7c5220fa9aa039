#include "saw/teleop/laws/surgical.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "saw/eigen.hpp"

namespace saw::teleop {
namespace {

constexpr double degrees = 180.0 / std::numbers::pi;

}  // namespace

SurgicalLaw::SurgicalLaw(const Settings& s, const LawContext& c) : s_(s), period_(c.period) {}

Eigen::Quaterniond SurgicalLaw::camera(const LawInputs& in) const noexcept {
  if (const Pose* endoscope = in.declared.get<Pose>(0)) return to_eigen(endoscope->orientation).normalized();
  const double r = s_.camera_rpy[0] / degrees, p = s_.camera_rpy[1] / degrees, y = s_.camera_rpy[2] / degrees;
  return Eigen::Quaterniond(Eigen::AngleAxisd(y, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(p, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(r, Eigen::Vector3d::UnitX()));
}

void SurgicalLaw::reset(const LawInputs& in) noexcept {
  // Held where it is until engaged: the goal stays this pose, so no drift and no step.
  p_s0_ = in.slave.position;
  q_s0_ = in.slave.orientation;
  jaw_ = in.slave.grip;  // NaN when the slave has no jaw: then none is sent
  p_goal_ = p_s0_;
  q_goal_ = q_s0_;
  engaged_ = false;
  // Reset runs every cycle the task holds (a clutch, a busy device): the move is sent by the step
  // after, once.
  align_pending_ = s_.orientation && s_.align_master;
  moving_master_ = false;  // held: the move, if any, is under way or over (the device says busy)
  // Engaged by the step (this cycle's inputs, never a held cycle's); told how far off meanwhile.
  (void)observe(in, camera(in));
}

void SurgicalLaw::align_master(const LawInputs& in, const Eigen::Quaterniond& c) noexcept {
  // Aligned when C · q_m = q_s0 (the master seen through the camera is the instrument).
  const Eigen::Quaterniond q = (c.conjugate() * q_s0_).normalized();
  // Not set for a master without move_cp: its wrench goes on, the operator turns it.
  if (in.master.position.allFinite() && q.coeffs().allFinite())
    moving_master_ = in.outputs.set(0, Pose{to_vec3(in.master.position), to_quat(q)});
}

Eigen::Quaterniond SurgicalLaw::observe(const LawInputs& in, const Eigen::Quaterniond& c) noexcept {
  const Eigen::Quaterniond seen = c * in.master.orientation;
  misalignment_ = s_.orientation ? seen.angularDistance(q_s0_) * degrees : 0.0;
  aligned_ = misalignment_ <= s_.align_tolerance ? 1.0 : 0.0;
  return seen;
}

bool SurgicalLaw::engage(const LawInputs& in, const Eigen::Quaterniond& c) noexcept {
  const Eigen::Quaterniond seen = observe(in, c);
  engaged_ = aligned_ == 1.0;
  if (!engaged_) return false;
  p_m0_ = in.master.position;
  c_ = c;
  // What is left of the misalignment is kept as an offset: the goal starts at q_s0.
  q_off_ = seen.conjugate() * q_s0_;
  return true;
}

double SurgicalLaw::jaw_goal(const LawInputs& in) noexcept {
  if (!std::isfinite(jaw_) || !std::isfinite(in.master.grip)) return jaw_;  // NaN: nothing sent
  const double target = std::clamp(s_.jaw_scale * in.master.grip + s_.jaw_offset, s_.jaw_min, s_.jaw_max);
  const double step = s_.jaw_rate * period_;
  jaw_ += std::clamp(target - jaw_, -step, step);
  return jaw_;
}

void SurgicalLaw::approach(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) noexcept {
  const Eigen::Vector3d d = p - p_goal_;
  const double reach = s_.max_linear_speed * period_, dist = d.norm();
  p_goal_ = dist <= reach ? p : Eigen::Vector3d(p_goal_ + d * (reach / dist));
  const double turn = s_.max_angular_speed * period_, angle = q_goal_.angularDistance(q);
  q_goal_ = angle <= turn ? q : q_goal_.slerp(turn / angle, q).normalized();
}

LawCommand SurgicalLaw::step(const LawInputs& in) noexcept {
  LawCommand out;
  out.orients_slave = true;
  const bool first = std::exchange(align_pending_, false);
  if (!engaged_) {
    const Eigen::Quaterniond c = camera(in);
    if (!engage(in, c) && first) align_master(in, c);
  }
  if (!engaged_) {
    approach(p_s0_, q_s0_);
  } else {
    approach(p_s0_ + s_.scale * (c_ * (in.master.position - p_m0_)),
             s_.orientation ? (c_ * in.master.orientation * q_off_).normalized() : q_s0_);
    out.slave_jaw = jaw_goal(in);
  }
  out.master_moving = moving_master_ && !engaged_;
  out.slave_goal = p_goal_;
  out.slave_goal_orientation = q_goal_;
  out.slave_error = in.slave.position - out.slave_goal;
  out.master_error = -out.slave_error / s_.scale;
  out.slave_offset = p_s0_ - s_.scale * (c_ * p_m0_);
  orientation_error_ = in.slave.orientation.angularDistance(out.slave_goal_orientation) * degrees;
  out.finite = out.slave_goal.allFinite() && out.slave_goal_orientation.coeffs().allFinite() &&
               out.slave_error.allFinite();
  if (!out.finite) out.bad_side = in.master.position.allFinite() ? FaultSide::slave : FaultSide::master;
  return out;
}

}  // namespace saw::teleop
