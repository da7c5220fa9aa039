// ArmKinematics: forward kinematics and Jacobian of a simulated 3-DOF haptic arm, via KDL.
#pragma once

#include <Eigen/Core>
#include <array>
#include <memory>
#include <string_view>

namespace saw::drivers {

enum class ArmModel : std::uint8_t {
  omni,    // Phantom Omni-like 3R arm: base yaw, shoulder pitch, elbow pitch, 133 mm links
  falcon,  // Falcon-sized workspace, modelled as three prismatic joints (not the real delta)
};

// All KDL buffers are sized in the constructor: fk() and jacobian() allocate nothing.
class ArmKinematics {
 public:
  explicit ArmKinematics(ArmModel model);
  ~ArmKinematics();
  ArmKinematics(const ArmKinematics&) = delete;
  ArmKinematics& operator=(const ArmKinematics&) = delete;

  ArmModel model() const noexcept { return model_; }
  // The joints' names, base to tip (measured_js carries them).
  std::array<std::string_view, 3> joint_names() const noexcept;
  Eigen::Vector3d fk(const Eigen::Vector3d& q) noexcept;
  // Linear part of the Jacobian: ẋ = J·q̇, τ = Jᵀ·f.
  Eigen::Matrix3d jacobian(const Eigen::Vector3d& q) noexcept;

 private:
  struct Kdl;
  ArmModel model_;
  std::unique_ptr<Kdl> kdl_;
};

}  // namespace saw::drivers
