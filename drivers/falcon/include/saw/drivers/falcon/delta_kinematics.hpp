// DeltaKinematics: the Falcon's three-arm rotary delta, encoders ↔ angles ↔ tip, and forces ↔ DAC.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace saw::drivers::falcon {

// The device's geometry and calibration: libnifalcon's Falcon (include/falcon/core/FalconGeometry.h,
// Begley's adjusted measurements; the letters are its names; tests/falcon/reference/README.md).
// The frame is libnifalcon's, absolute: the origin on the delta's axis in the motors' plane, z
// along the axis towards the grip, x to the right (arm 0 at the top). Encoder counts 0 (every arm
// at 35°) put the tip at (0, 0, 134.6 mm).
//
// Each leg i, in its own frame (u radial, v along the motor axis, w = z), obtained by turning
// the point by −azimuth[i] and taking off (base_radius, base_offset, 0): θ1 the arm (motor)
// angle, θ3 the parallelogram's angle about its own axis, θ2 the shin's elevation, and
//   u = a cos θ1 − c + K cos θ2,  v = b cos θ3 − f,  w = a sin θ1 + K sin θ2,  K = d + e + b sin θ3.
struct DeltaGeometry {
  double upper_arm = 0.060;          // m, motor axis to knee ("a")
  double lower_arm = 0.1025;         // m, the parallelogram's side ("b")
  double base_radius = 0.040;        // m, delta axis to each motor's axis, radial ("r")
  double base_offset = -0.02309;     // m, the same along the motor axis ("s")
  double effector_radius = 0.01443;  // m, grip centre to each parallelogram's lower joint, radial ("c")
  double effector_offset = -0.025;   // m, the same along the motor axis ("f")
  double knee_offset = 0.01125;      // m, knee to the parallelogram's upper joints ("e")
  double shin_offset = 0.01125;      // m, the parallelogram's lower joints to the effector ("d")
  // The three arms' directions around the axis (rad): 90°, -30°, -150°, each turned by 15°.
  std::array<double, 3> azimuth{1.8325957145940461, -0.2617993877991494, -2.3561944901923448};
  // Encoder → arm angle: 320 slots × 4 (quadrature) per motor turn, reduced by the capstan
  // (shaft ⌀ 14.25 mm on arm ⌀ 110 mm); an encoder count of 0 is at 35° once homed.
  double counts_per_motor_turn = 1280;
  double capstan_ratio = 0.01425 / 0.110;
  double angle_at_zero = 0.6108652381980153;  // rad (35°)
  // Arm torque (N·m) → DAC count: libnifalcon's scale and sign (-10000), and the DAC's range.
  double dac_per_newton_metre = -10000;
  int dac_limit = 4096;
};

// Allocation-free: every function works on fixed-size Eigen values.
class DeltaKinematics {
 public:
  explicit DeltaKinematics(DeltaGeometry g = {}) noexcept : g_(g) {}
  const DeltaGeometry& geometry() const noexcept { return g_; }

  double angle(std::int16_t encoder) const noexcept;
  std::int16_t encoder(double angle) const noexcept;  // rounded, wrapped to 16 bits as the firmware does
  Eigen::Vector3d angles(const std::array<std::int16_t, 3>& encoders) const noexcept;

  // Tip position for arm angles; false when the three arms cannot meet (out of the model).
  // Newton's method on inverse() (no closed form with the offsets): at most 40 steps from the
  // workspace's middle, or from `seed` (the last tip: about 2 steps in a cycle), falling back
  // to the middle when the seed does not converge.
  bool forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x) const noexcept;
  bool forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x, const Eigen::Vector3d& seed) const noexcept;
  // Arm angles for a tip position (knees outwards); false when out of reach.
  bool inverse(const Eigen::Vector3d& x, Eigen::Vector3d& theta) const noexcept;
  // ẋ = J·θ̇ at (θ, x = forward(θ)); τ = Jᵀ·f. False at a singularity. J is computed at x.
  bool jacobian(const Eigen::Vector3d& theta, const Eigen::Vector3d& x, Eigen::Matrix3d& j) const noexcept;

  // Force at the tip (N) → arm torques → DAC counts, scaled down together (direction kept) when
  // one would exceed the DAC's range. Returns the scale applied (1: none).
  double dac(const Eigen::Matrix3d& j, const Eigen::Vector3d& force,
             std::array<std::int16_t, 3>& out) const noexcept;
  // The inverse, for the simulated firmware: DAC counts → arm torques (N·m).
  Eigen::Vector3d torque(const std::array<std::int16_t, 3>& dac) const noexcept;

 private:
  // Leg i's angles (θ1, θ2, θ3) for the tip x; false when out of its reach.
  bool leg(int i, const Eigen::Vector3d& x, Eigen::Vector3d& angles) const noexcept;
  bool newton(const Eigen::Vector3d& theta, Eigen::Vector3d& x, Eigen::Vector3d p) const noexcept;
  // dθ1ᵢ/dx, row i; false when out of reach or singular.
  bool angle_rates(const Eigen::Vector3d& x, Eigen::Matrix3d& dtheta_dx) const noexcept;

  DeltaGeometry g_;
};

}  // namespace saw::drivers::falcon
