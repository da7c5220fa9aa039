#include "saw/teleop/teleop_law.hpp"

#include <algorithm>
#include <cmath>

namespace saw::teleop {

Eigen::Vector3d Scale::master_to_slave() const {
  return Eigen::Vector3d(mirror[0], mirror[1], mirror[2]) * scale;
}

Eigen::Vector3d Scale::slave_to_master() const { return master_to_slave().cwiseInverse(); }

bool Scale::valid() const {
  if (!(scale >= min_scale && scale <= max_scale)) return false;  // NaN fails too
  return std::all_of(mirror.begin(), mirror.end(), [](double m) { return m == 1.0 || m == -1.0; });
}

bool Gains::valid() const { return master >= 0 && master <= max_gain && slave >= 0 && slave <= max_gain; }

bool ForceLimits::valid() const {
  return master >= 0 && master <= max_force_limit && slave >= 0 && slave <= max_force_limit;
}

Eigen::Vector3d saturate(const Eigen::Vector3d& f, double limit) {
  if (!f.allFinite() || !std::isfinite(limit) || limit <= 0) return Eigen::Vector3d::Zero();
  const double n = f.norm();
  if (!std::isfinite(n)) return Eigen::Vector3d::Zero();  // finite components, overflowing norm
  return n > limit ? Eigen::Vector3d(f * (limit / n)) : f;
}

LawOutput compute_law(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                      const Eigen::Vector3d& p_slave, const Eigen::Vector3d& o_slave, const Scale& s,
                      const Gains& k, const ForceLimits& lim) {
  const Eigen::Vector3d d_m = p_master + o_master;  // (1)
  const Eigen::Vector3d d_s = p_slave + o_slave;    // (2)
  LawOutput out;
  out.master_error = d_m - s.slave_to_master().cwiseProduct(d_s);  // (3)
  out.slave_error = d_s - s.master_to_slave().cwiseProduct(d_m);   // (4)
  const Eigen::Vector3d f_m = -k.master * out.master_error;
  const Eigen::Vector3d f_s = -k.slave * out.slave_error;
  out.master_force = saturate(f_m, lim.master);  // (5)
  out.slave_force = saturate(f_s, lim.slave);    // (6)
  out.master_saturated = f_m.norm() > lim.master;
  out.slave_saturated = f_s.norm() > lim.slave;
  out.finite = out.master_error.allFinite() && out.slave_error.allFinite() && f_m.allFinite() &&
               f_s.allFinite() && std::isfinite(f_m.norm()) && std::isfinite(f_s.norm());
  return out;
}

Eigen::Vector3d cancelling_slave_offset(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                                        const Eigen::Vector3d& p_slave, const Scale& s) {
  return s.master_to_slave().cwiseProduct(p_master + o_master) - p_slave;
}

Eigen::Vector3d ratchet_shift(const LawOutput& e, const Scale& s, const Gains& k, const ForceLimits& lim) {
  const double fm = k.master * e.master_error.norm();
  const double fs = k.slave * e.slave_error.norm();
  double alpha = 1.0;
  if (fm > lim.master) alpha = std::min(alpha, lim.master / fm);
  if (fs > lim.slave) alpha = std::min(alpha, lim.slave / fs);
  // e_m' = e_m − S·Δo_s = α·e_m  ⇒  Δo_s = (1 − α)·S⁻¹·e_m.
  return (1.0 - alpha) * s.master_to_slave().cwiseProduct(e.master_error);
}

}  // namespace saw::teleop
