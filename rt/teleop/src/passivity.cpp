#include "saw/teleop/passivity.hpp"

#include <algorithm>
#include <cmath>

namespace saw::teleop {

PassivityController::Step PassivityController::step(const Eigen::Vector3d& force,
                                                    const Eigen::Vector3d& velocity, double remote_in,
                                                    double dt) noexcept {
  Step s{force, 0};
  damping_ = 0;
  if (!(dt > 0)) return s;
  const double power = force.dot(velocity);  // out of the network into the device
  if (power <= 0) {
    energy_.in -= power * dt;
    margin_ = remote_in - energy_.out;
    return s;
  }
  // What this step would give out beyond what has come in at the other port: take it out by
  // damping (only this step's output can be reduced, not what went before).
  const double wanted = power * dt;
  const double excess = std::clamp(energy_.out + wanted - remote_in, 0.0, wanted);
  const double v2 = velocity.squaredNorm();
  if (excess > 0 && v2 > 0) {
    s.damping = std::min(excess / (dt * v2), max_damping_);
    s.force = force - s.damping * velocity;
  }
  damping_ = s.damping;
  const double taken = s.damping * v2 * dt;
  energy_.out += wanted - taken;
  dissipated_ += taken;
  margin_ = remote_in - energy_.out;
  return s;
}

}  // namespace saw::teleop
