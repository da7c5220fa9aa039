#include "saw/drivers/falcon/delta_kinematics.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace saw::drivers::falcon {

double DeltaKinematics::angle(std::int16_t encoder) const noexcept {
  return g_.angle_at_zero + encoder * (2 * std::numbers::pi / g_.counts_per_motor_turn) * g_.capstan_ratio;
}

std::int16_t DeltaKinematics::encoder(double a) const noexcept {
  const double counts =
      (a - g_.angle_at_zero) / ((2 * std::numbers::pi / g_.counts_per_motor_turn) * g_.capstan_ratio);
  return static_cast<std::int16_t>(
      static_cast<std::uint16_t>(static_cast<std::int64_t>(std::lround(counts)) & 0xffff));
}

Eigen::Vector3d DeltaKinematics::angles(const std::array<std::int16_t, 3>& e) const noexcept {
  return {angle(e[0]), angle(e[1]), angle(e[2])};
}

Eigen::Vector3d DeltaKinematics::radial(int i) const noexcept {
  const double a = g_.azimuth[static_cast<std::size_t>(i)];
  return {std::cos(a), std::sin(a), 0};
}

Eigen::Vector3d DeltaKinematics::knee(int i, double theta) const noexcept {
  const Eigen::Vector3d u = radial(i);
  return (g_.base_radius - g_.effector_radius + g_.upper_arm * std::cos(theta)) * u +
         Eigen::Vector3d(0, 0, g_.upper_arm * std::sin(theta));
}

Eigen::Vector3d DeltaKinematics::knee_rate(int i, double theta) const noexcept {
  return -g_.upper_arm * std::sin(theta) * radial(i) + Eigen::Vector3d(0, 0, g_.upper_arm * std::cos(theta));
}

// The tip is where three spheres (radius lower_arm, centred on the shifted knees) meet: the
// intersection further along +z (the grip hangs below the motors).
bool DeltaKinematics::forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x) const noexcept {
  const Eigen::Vector3d p1 = knee(0, theta[0]), p2 = knee(1, theta[1]), p3 = knee(2, theta[2]);
  const double d = (p2 - p1).norm();
  if (!(d > 1e-12)) return false;
  const Eigen::Vector3d ex = (p2 - p1) / d;
  const double i = ex.dot(p3 - p1);
  Eigen::Vector3d ey = p3 - p1 - i * ex;
  const double jn = ey.norm();
  if (!(jn > 1e-12)) return false;
  ey /= jn;
  const Eigen::Vector3d ez = ex.cross(ey);
  const double r2 = g_.lower_arm * g_.lower_arm;
  const double px = d / 2;  // equal radii
  const double py = (i * i + jn * jn) / (2 * jn) - (i / jn) * px;
  const double pz2 = r2 - px * px - py * py;
  if (!(pz2 >= 0)) return false;
  const Eigen::Vector3d c = p1 + px * ex + py * ey;
  const double pz = std::sqrt(pz2);
  const Eigen::Vector3d a = c + pz * ez, b = c - pz * ez;
  x = a.z() > b.z() ? a : b;
  return x.allFinite();
}

bool DeltaKinematics::inverse(const Eigen::Vector3d& x, Eigen::Vector3d& theta) const noexcept {
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d u = radial(i);
    const Eigen::Vector3d v = x - (g_.base_radius - g_.effector_radius) * u;
    const double vu = v.dot(u), vz = v.z();
    const double rho = std::hypot(vu, vz);
    const double k =
        (v.squaredNorm() + g_.upper_arm * g_.upper_arm - g_.lower_arm * g_.lower_arm) / (2 * g_.upper_arm);
    if (!(rho > 0) || std::abs(k) > rho) return false;
    theta[i] = std::atan2(vz, vu) - std::acos(k / rho);  // the knee outwards
  }
  return theta.allFinite();
}

// Each arm's constraint |x − kᵢ(θᵢ)|² = b² differentiated: (x − kᵢ)ᵀ·ẋ = (x − kᵢ)ᵀ·kᵢ'·θ̇ᵢ.
bool DeltaKinematics::jacobian(const Eigen::Vector3d& theta, const Eigen::Vector3d& x,
                               Eigen::Matrix3d& j) const noexcept {
  Eigen::Matrix3d a;
  Eigen::Matrix3d d = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d r = x - knee(i, theta[i]);
    a.row(i) = r.transpose();
    d(i, i) = r.dot(knee_rate(i, theta[i]));
  }
  const double det = a.determinant();
  if (!(std::abs(det) > 1e-12)) return false;
  j = a.inverse() * d;
  return j.allFinite();
}

double DeltaKinematics::dac(const Eigen::Matrix3d& j, const Eigen::Vector3d& force,
                            std::array<std::int16_t, 3>& out) const noexcept {
  Eigen::Vector3d counts = g_.dac_per_newton_metre * (j.transpose() * force);
  if (!counts.allFinite()) {  // never a NaN on the motors: no force instead
    out = {};
    return 0;
  }
  const double largest = counts.cwiseAbs().maxCoeff();
  const double scale = largest > g_.dac_limit ? g_.dac_limit / largest : 1.0;
  counts *= scale;
  for (int i = 0; i < 3; ++i)
    out[static_cast<std::size_t>(i)] = static_cast<std::int16_t>(std::lround(counts[i]));
  return scale;
}

Eigen::Vector3d DeltaKinematics::torque(const std::array<std::int16_t, 3>& dac) const noexcept {
  return Eigen::Vector3d(dac[0], dac[1], dac[2]) / g_.dac_per_newton_metre;
}

}  // namespace saw::drivers::falcon
