// ArmKinematics: forward and inverse kinematics and Jacobian of a simulated 3-DOF haptic arm.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string_view>

namespace saw::drivers {

enum class ArmModel : std::uint8_t {
  omni,    // Phantom Omni-like 3R arm (KDL): base yaw, shoulder pitch, elbow pitch, 133 mm links
  falcon,  // Novint Falcon: the rotary delta (drivers/falcon's kinematics), joints = arm angles
};

// Positions in the frame the real device's driver reports: the Omni's base; for the Falcon, the
// tip relative to its pose with every arm at 35° (encoder count 0), as the `falcon` component.
// Every buffer is sized in the constructor: fk(), ik() and jacobian() allocate nothing.
class ArmKinematics {
 public:
  explicit ArmKinematics(ArmModel model);
  ~ArmKinematics();
  ArmKinematics(const ArmKinematics&) = delete;
  ArmKinematics& operator=(const ArmKinematics&) = delete;

  ArmModel model() const noexcept { return model_; }
  // The joints' names, base to tip (measured_js carries them).
  std::array<std::string_view, 3> joint_names() const noexcept;
  // For a Falcon q where the three arms cannot meet (outside the stops): the last pose computed.
  Eigen::Vector3d fk(const Eigen::Vector3d& q) noexcept;
  // Joints for a position (Omni: elbow bent downwards, q₂ > 0; Falcon: knees outwards);
  // false when out of reach.
  bool ik(const Eigen::Vector3d& x, Eigen::Vector3d& q) noexcept;
  // Linear part of the Jacobian: ẋ = J·q̇, τ = Jᵀ·f (zero at a Falcon singularity).
  Eigen::Matrix3d jacobian(const Eigen::Vector3d& q) noexcept;

 private:
  struct Kdl;
  struct Delta;
  ArmModel model_;
  std::unique_ptr<Kdl> kdl_;
  std::unique_ptr<Delta> delta_;
};

}  // namespace saw::drivers
