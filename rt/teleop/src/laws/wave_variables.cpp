#include "saw/teleop/laws/wave_variables.hpp"

#include <cmath>

#include "saw/eigen.hpp"

namespace saw::teleop {

void WaveVariableLaw::reset(const LawInputs& in) noexcept {
  desired_ = in.slave.position;
  offset_ = in.slave.position - in.master.position;
}

LawCommand WaveVariableLaw::step(const LawInputs& in) noexcept {
  LawCommand out;
  const double b = s_.impedance, root = std::sqrt(2 * b);
  const Vec3* wave = in.declared.get<Vec3>(0);
  const Eigen::Vector3d u =
      wave != nullptr && in.declared.fresh(0) ? to_eigen(*wave) : Eigen::Vector3d::Zero();
  // F = K·(x_d + dt·ẋ_d − x_s) + B·(ẋ_d − ẋ_s) with ẋ_d = (√(2b)·u − F)/b, solved for F.
  const double c = s_.stiffness * dt_ + s_.damping;
  const Eigen::Vector3d unsaturated =
      (s_.stiffness * (desired_ - in.slave.position) - s_.damping * in.slave.velocity + c * root * u / b) /
      (1 + c / b);
  const Eigen::Vector3d f = saturate(unsaturated, s_.force_limit);
  const Eigen::Vector3d velocity = (root * u - f) / b;  // ẋ_d, consistent with the force applied
  desired_ += dt_ * velocity;
  out.slave_force = f;
  const Eigen::Vector3d v = u - f * (root / b);  // v = (b·ẋ_d − F)/√(2b)
  out.limiting = unsaturated.norm() > s_.force_limit;
  out.slave_error = in.slave.position - (in.master.position + offset_);
  out.master_error = -out.slave_error;
  out.slave_offset = offset_;
  out.finite = unsaturated.allFinite() && std::isfinite(unsaturated.norm()) && desired_.allFinite();
  if (!out.finite) {
    out.bad_side = u.allFinite() ? FaultSide::slave : FaultSide::master;
    out.slave_force.setZero();
    desired_ = in.slave.position;
    return out;
  }
  (void)in.outputs.set(0, to_vec3(v));
  return out;
}

}  // namespace saw::teleop
