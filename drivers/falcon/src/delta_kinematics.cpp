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

// Leg i's constraint with θ1 alone left: the knee (a cos θ1, a sin θ1) and the shin's lower end
// (u + c, w) are K apart, K = d + e + b sin θ3 fixed by v. With t = tan(θ1/2) that is
// l2 t² + l1 t + l0 = 0 (Stamper's thesis; libnifalcon's IK). Its root with the knee outwards is
// (−l1 − √disc)/(2 l2), taken here as 2 l0/(−l1 + √disc): the same number without the
// cancellation near θ1 = 0 (it cost 1e-6 of relative accuracy: the reference's README).
bool DeltaKinematics::leg(int i, const Eigen::Vector3d& x, Eigen::Vector3d& angles) const noexcept {
  const double phi = g_.azimuth[static_cast<std::size_t>(i)];
  const double cp = std::cos(phi), sp = std::sin(phi);
  const double u = cp * x.x() + sp * x.y() - g_.base_radius;
  const double v = -sp * x.x() + cp * x.y() - g_.base_offset;
  const double w = x.z();
  const double a = g_.upper_arm, b = g_.lower_arm, c = g_.effector_radius;
  const double q = (v + g_.effector_offset) / b;
  if (!(q > -1 && q < 1)) return false;
  const double th3 = std::acos(q);
  const double k = g_.shin_offset + g_.knee_offset + b * std::sin(th3);
  const double l0 = (u + c - a) * (u + c - a) + w * w - k * k;
  const double l1 = -4 * a * w;
  const double l2 = (u + c + a) * (u + c + a) + w * w - k * k;
  const double disc = l1 * l1 - 4 * l0 * l2;
  const double den = -l1 + std::sqrt(disc);
  if (!(disc >= 0) || !(std::abs(den) > 0)) return false;
  const double th1 = 2 * std::atan(2 * l0 / den);
  const double th2 = std::atan2(w - a * std::sin(th1), u + c - a * std::cos(th1));
  angles = {th1, th2, th3};
  return angles.allFinite();
}

bool DeltaKinematics::inverse(const Eigen::Vector3d& x, Eigen::Vector3d& theta) const noexcept {
  Eigen::Vector3d t;
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d l;
    if (!leg(i, x, l)) return false;
    t[i] = l[0];
  }
  theta = t;
  return true;
}

// The leg's constraint g = (u + c − a cos θ1)² + (w − a sin θ1)² − K(v)² = 0 differentiated:
// ∂g/∂θ1 = 2aK·sin(θ1 − θ2) and ∂g/∂(u, v, w) = 2K·(cos θ2, cot θ3, sin θ2), so
// dθ1/d(u, v, w) = −(cos θ2, cot θ3, sin θ2) / (a sin(θ1 − θ2)), turned back by the azimuth.
bool DeltaKinematics::angle_rates(const Eigen::Vector3d& x, Eigen::Matrix3d& m) const noexcept {
  for (int i = 0; i < 3; ++i) {
    Eigen::Vector3d l;
    if (!leg(i, x, l)) return false;
    const double den = g_.upper_arm * std::sin(l[0] - l[1]);
    const double s3 = std::sin(l[2]);
    if (!(std::abs(den) > 1e-12) || !(std::abs(s3) > 1e-12)) return false;
    const double du = -std::cos(l[1]) / den, dv = -(std::cos(l[2]) / s3) / den, dw = -std::sin(l[1]) / den;
    const double phi = g_.azimuth[static_cast<std::size_t>(i)];
    const double cp = std::cos(phi), sp = std::sin(phi);
    m.row(i) << du * cp - dv * sp, du * sp + dv * cp, dw;
  }
  return m.allFinite();
}

// No closed form with the offsets: Newton's method on inverse() from the workspace's middle,
// halving a step that leaves the model or does not bring the angles closer. It converges in
// about 6 steps over the workspace; the bounds keep the cycle's cost bounded when it cannot.
bool DeltaKinematics::forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x) const noexcept {
  return newton(theta, x, Eigen::Vector3d(0, 0, 0.11));
}

bool DeltaKinematics::forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x,
                              const Eigen::Vector3d& seed) const noexcept {
  return (seed.allFinite() && newton(theta, x, seed)) || forward(theta, x);
}

bool DeltaKinematics::newton(const Eigen::Vector3d& theta, Eigen::Vector3d& x,
                             Eigen::Vector3d p) const noexcept {
  constexpr int max_steps = 40, max_halvings = 30;
  constexpr double tolerance = 1e-12;  // rad
  Eigen::Vector3d t;
  if (!inverse(p, t)) return false;
  Eigen::Vector3d residual = t - theta;
  for (int step = 0; step < max_steps; ++step) {
    if (residual.cwiseAbs().maxCoeff() < tolerance) {
      x = p;
      return true;
    }
    Eigen::Matrix3d m;
    if (!angle_rates(p, m)) return false;
    const Eigen::Vector3d dx = m.partialPivLu().solve(residual);
    double lambda = 1;
    bool better = false;
    for (int h = 0; h < max_halvings && !better; ++h, lambda /= 2) {
      const Eigen::Vector3d candidate = p - lambda * dx;
      Eigen::Vector3d tc;
      if (inverse(candidate, tc) && (tc - theta).norm() < residual.norm()) {
        p = candidate;
        residual = tc - theta;
        better = true;
      }
    }
    if (!better) break;  // at the limit of double precision, or no way closer
  }
  if (!(residual.cwiseAbs().maxCoeff() < 1e-9)) return false;
  x = p;
  return x.allFinite();
}

bool DeltaKinematics::jacobian(const Eigen::Vector3d&, const Eigen::Vector3d& x,
                               Eigen::Matrix3d& j) const noexcept {
  Eigen::Matrix3d m;
  if (!angle_rates(x, m)) return false;
  const double det = m.determinant();
  if (!(std::abs(det) > 1e-12)) return false;
  j = m.inverse();
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
