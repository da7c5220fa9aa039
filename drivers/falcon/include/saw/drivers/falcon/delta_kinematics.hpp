// DeltaKinematics: the Falcon's three-arm rotary delta, encoders ↔ angles ↔ tip, and forces ↔ DAC.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace saw::drivers::falcon {

// The device's geometry and calibration (defaults: libnifalcon's documented Falcon figures).
// The frame: z along the delta's axis, from the motors towards the grip; x to the right.
struct DeltaGeometry {
  double upper_arm = 0.060;          // m, motor axis to knee ("a")
  double lower_arm = 0.1025;         // m, the parallelogram's side ("b")
  double base_radius = 0.040;        // m, delta axis to each motor's axis ("r")
  double effector_radius = 0.01443;  // m, grip centre to each parallelogram's lower joint ("c")
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
  bool forward(const Eigen::Vector3d& theta, Eigen::Vector3d& x) const noexcept;
  // Arm angles for a tip position (knees outwards); false when out of reach.
  bool inverse(const Eigen::Vector3d& x, Eigen::Vector3d& theta) const noexcept;
  // ẋ = J·θ̇ at (θ, x = forward(θ)); τ = Jᵀ·f. False at a singularity.
  bool jacobian(const Eigen::Vector3d& theta, const Eigen::Vector3d& x, Eigen::Matrix3d& j) const noexcept;

  // Force at the tip (N) → arm torques → DAC counts, scaled down together (direction kept) when
  // one would exceed the DAC's range. Returns the scale applied (1: none).
  double dac(const Eigen::Matrix3d& j, const Eigen::Vector3d& force,
             std::array<std::int16_t, 3>& out) const noexcept;
  // The inverse, for the simulated firmware: DAC counts → arm torques (N·m).
  Eigen::Vector3d torque(const std::array<std::int16_t, 3>& dac) const noexcept;

 private:
  Eigen::Vector3d radial(int i) const noexcept;
  // Centre of arm i's lower-arm sphere, relative to the tip: the knee moved in by the effector.
  Eigen::Vector3d knee(int i, double theta) const noexcept;
  Eigen::Vector3d knee_rate(int i, double theta) const noexcept;  // d knee / dθ

  DeltaGeometry g_;
};

}  // namespace saw::drivers::falcon
