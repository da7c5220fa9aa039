// DeltaArmDynamics: the Falcon's per-arm inertia, friction and stops, for its simulations.
#pragma once

namespace saw::drivers::falcon {

// Joint space, one rotary arm (motor through the capstan, arm, a third of the parallelogram and
// grip): θ̈ = (τ − damping·θ̇) / inertia, between the stops. Estimates, not identified on a
// device: a motor rotor of about 2·10⁻⁶ kg·m² seen through the capstan's 7.7:1 (1.2·10⁻⁴) plus
// the arm, capstan sector and moving links. At the workspace centre they come to 0.09–0.16 kg
// and 0.9–1.6 N·s/m at the grip (Jacobian at the arms' 35°), the feel of a light consumer
// device's grip; the first thing to measure on a real Falcon.
struct DeltaArmDynamics {
  double inertia = 4e-4;  // kg·m² per arm, at the arm's axis
  double damping = 4e-3;  // N·m·s/rad per arm
  // rad: the mechanical stops. Between them the three arms always meet (forward() succeeds).
  double angle_min = 0.2, angle_max = 1.1;
};

}  // namespace saw::drivers::falcon
