// TeleopLaw: the paper's collaborative force law (eqs. 1-6) in 3-D, read consistently.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "saw/crtk.hpp"

namespace saw::teleop {

// Per-axis map from master to slave displacements: slave moves `scale` times the master,
// with a sign flip on mirrored axes (devices facing each other). S⁻¹ = diag(mirror·scale).
struct Scale {
  double scale = 1.0;
  Vec3 mirror{1, 1, 1};

  Eigen::Vector3d master_to_slave() const;  // S⁻¹ as a diagonal
  Eigen::Vector3d slave_to_master() const;  // S
  bool valid() const;                       // finite, non-zero scale; mirror entries ±1
};

struct Gains {
  static constexpr std::uint32_t layout_version = 1;
  double master = 100.0;  // k_m, N/m
  double slave = 100.0;   // k_s, N/m
};

struct ForceLimits {
  static constexpr std::uint32_t layout_version = 1;
  double master = 3.0;  // lim_m, N (magnitude)
  double slave = 3.0;   // lim_s, N
};

struct LawOutput {
  Eigen::Vector3d master_error, slave_error;  // e_m, e_s
  Eigen::Vector3d master_force, slave_force;  // f_m, f_s after saturation
  bool master_saturated = false, slave_saturated = false;
};

// With d = p + o: e_m = d_m − S·d_s, e_s = d_s − S⁻¹·d_m, f = −k·e saturated to magnitude lim.
// The paper prints e_s = d_s − (−sc)·d_m and f = max(k·e, lim); read literally the errors
// would not vanish at the same pose and max would never limit: S⁻¹ and a magnitude
// saturation are the consistent reading (docs/architecture.md).
LawOutput compute_law(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                      const Eigen::Vector3d& p_slave, const Eigen::Vector3d& o_slave, const Scale& s,
                      const Gains& k, const ForceLimits& lim);

// Saturates a force to magnitude `limit`, keeping its direction.
Eigen::Vector3d saturate(const Eigen::Vector3d& f, double limit);

// The slave offset that makes both errors zero for these positions (used on enable, clutch).
Eigen::Vector3d cancelling_slave_offset(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                                        const Eigen::Vector3d& p_slave, const Scale& s);

// Ratchet: the slave-offset shift that brings both unsaturated forces back to their limits
// (both errors shrink by the same factor, since e_s = −S⁻¹·e_m). Zero when within limits.
Eigen::Vector3d ratchet_shift(const LawOutput& unsaturated_errors, const Scale& s, const Gains& k,
                              const ForceLimits& lim);

}  // namespace saw::teleop
