#include "saw/teleop/laws/wave_variables.hpp"

#include <cmath>

namespace saw::teleop {

void WaveVariableLaw::reset(const LawInputs& in) noexcept {
  desired_ = in.slave.position;
  offset_ = in.slave.position - in.master.position;
}

LawCommand WaveVariableLaw::step(const LawInputs& in) noexcept {
  LawCommand out;
  const double b = s_.impedance, root = std::sqrt(2 * b);
  const Eigen::Vector3d u = in.master_wave_fresh ? in.master_wave : Eigen::Vector3d::Zero();
  // F = K·(x_d + dt·ẋ_d − x_s) + B·(ẋ_d − ẋ_s) with ẋ_d = (√(2b)·u − F)/b, solved for F.
  const double c = s_.stiffness * dt_ + s_.damping;
  const Eigen::Vector3d unsaturated =
      (s_.stiffness * (desired_ - in.slave.position) - s_.damping * in.slave.velocity + c * root * u / b) /
      (1 + c / b);
  const Eigen::Vector3d f = saturate(unsaturated, s_.force_limit);
  const Eigen::Vector3d velocity = (root * u - f) / b;  // ẋ_d, consistent with the force applied
  desired_ += dt_ * velocity;
  out.slave_force = f;
  out.master_wave_out = u - f * (root / b);  // v = (b·ẋ_d − F)/√(2b)
  out.sends_wave = true;
  out.limiting = unsaturated.norm() > s_.force_limit;
  out.slave_error = in.slave.position - (in.master.position + offset_);
  out.master_error = -out.slave_error;
  out.slave_offset = offset_;
  out.finite = unsaturated.allFinite() && std::isfinite(unsaturated.norm()) && desired_.allFinite();
  if (!out.finite) {
    out.bad_side = in.master_wave.allFinite() ? FaultSide::slave : FaultSide::master;
    out.slave_force.setZero();
    out.sends_wave = false;
    desired_ = in.slave.position;
  }
  return out;
}

}  // namespace saw::teleop
