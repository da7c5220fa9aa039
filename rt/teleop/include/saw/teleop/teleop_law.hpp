// TeleopLaw: the paper's collaborative force law (eqs. 1-6) in 3-D, read consistently.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <tuple>

#include "saw/crtk.hpp"

namespace saw::teleop {

// Upper bounds of the settings, for the deployment file and the run-time set_* commands alike:
// beyond them a typo (a gain of 3e5 for 3e2) would make the loop unstable or the device violent.
inline constexpr double min_scale = 1e-3;
inline constexpr double max_scale = 1e3;
inline constexpr double max_gain = 1e4;         // N/m
inline constexpr double max_force_limit = 100;  // N
inline constexpr double max_horizon = 1.0;      // s, prediction

// Per-axis map from master to slave displacements: slave moves `scale` times the master,
// with a sign flip on mirrored axes (devices facing each other). S⁻¹ = diag(mirror·scale).
struct Scale {
  double scale = 1.0;
  Vec3 mirror{1, 1, 1};

  Eigen::Vector3d master_to_slave() const;  // S⁻¹ as a diagonal
  Eigen::Vector3d slave_to_master() const;  // S
  bool valid() const;                       // scale finite, within [min_scale, max_scale]; mirror entries ±1
};

struct Gains {
  static constexpr std::string_view type_name = "saw::teleop::Gains";
  static constexpr std::uint32_t layout_version = 1;
  double master = 100.0;                                                     // k_m, N/m
  double slave = 100.0;                                                      // k_s, N/m
  static constexpr auto fields = std::tuple{&Gains::master, &Gains::slave};  // checked across processes

  bool valid() const;  // finite, within [0, max_gain]
};
// Gains and ForceLimits cross processes byte for byte (set_gains, set_force_limits).
static_assert(sizeof(Gains) == 16 && offsetof(Gains, slave) == 8);

struct ForceLimits {
  static constexpr std::string_view type_name = "saw::teleop::ForceLimits";
  static constexpr std::uint32_t layout_version = 1;
  double master = 3.0;  // lim_m, N (magnitude)
  double slave = 3.0;   // lim_s, N
  static constexpr auto fields = std::tuple{&ForceLimits::master, &ForceLimits::slave};

  bool valid() const;  // finite, within [0, max_force_limit]
};
static_assert(sizeof(ForceLimits) == 16 && offsetof(ForceLimits, slave) == 8);

struct LawOutput {
  Eigen::Vector3d master_error, slave_error;  // e_m, e_s
  Eigen::Vector3d master_force, slave_force;  // f_m, f_s after saturation
  bool master_saturated = false, slave_saturated = false;
  // Errors and unsaturated forces all finite: when false, the forces are zero and must not be
  // trusted (a huge input overflowed, or an offset went bad).
  bool finite = true;
};

// With d = p + o: e_m = d_m − S·d_s, e_s = d_s − S⁻¹·d_m, f = −k·e saturated to magnitude lim.
// The paper prints e_s = d_s − (−sc)·d_m and f = max(k·e, lim); read literally the errors
// would not vanish at the same pose and max would never limit: S⁻¹ and a magnitude
// saturation are the consistent reading (docs/architecture.md).
LawOutput compute_law(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                      const Eigen::Vector3d& p_slave, const Eigen::Vector3d& o_slave, const Scale& s,
                      const Gains& k, const ForceLimits& lim);

// Saturates a force to magnitude `limit`, keeping its direction. A force that is not finite, or
// a limit that is not, gives zero: NaN never passes a comparison, so it is tested for first.
Eigen::Vector3d saturate(const Eigen::Vector3d& f, double limit);

// The slave offset that makes both errors zero for these positions (used on enable, clutch).
Eigen::Vector3d cancelling_slave_offset(const Eigen::Vector3d& p_master, const Eigen::Vector3d& o_master,
                                        const Eigen::Vector3d& p_slave, const Scale& s);

// Ratchet: the slave-offset shift that brings both unsaturated forces back to their limits
// (both errors shrink by the same factor, since e_s = −S⁻¹·e_m). Zero when within limits.
Eigen::Vector3d ratchet_shift(const LawOutput& unsaturated_errors, const Scale& s, const Gains& k,
                              const ForceLimits& lim);

}  // namespace saw::teleop
