// Wave variables: the scattering transform that makes a delayed channel passive by construction
// (Niemeyer & Slotine 1991) — the master's end, as pure functions.
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace saw::teleop::wave {

// At a port moving at velocity ẋ and resisted by force F (what the network exerts against the
// motion), with wave impedance b: u = (b·ẋ + F)/√(2b) leaves, v = (b·ẋ − F)/√(2b) arrives, and
// the power into the network is ẋ·F = ½|u|² − ½|v|²: a delay that passes u and v on unchanged
// (or drops them: zero) stores or loses energy, never makes it.
struct MasterEnd {
  Eigen::Vector3d force;  // N, to apply to the device (−F: against the motion when v is zero)
  Eigen::Vector3d u;      // the wave to send
};

// The master's end: its velocity in, the returning wave v in (zero in a cycle none arrived). The
// force is limited to `limit` (a device's own); u is then made from the force applied, so that
// the slave's end sees what the operator felt.
inline MasterEnd master_end(double b, const Eigen::Vector3d& velocity, const Eigen::Vector3d& v,
                            double limit) noexcept {
  const double root = std::sqrt(2 * b);
  Eigen::Vector3d resist = b * velocity - root * v;
  const double n = resist.norm();
  if (n > limit) resist *= limit / n;
  return {-resist, (b * velocity + resist) / root};
}

}  // namespace saw::teleop::wave
