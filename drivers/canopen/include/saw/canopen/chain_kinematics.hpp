// A serial chain described as URDF describes its joints, and its kinematics through KDL.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "saw/crtk.hpp"

namespace saw::canopen {

// One joint, as a URDF <joint> says it: its origin (xyz in m, rpy in rad: roll about x, pitch
// about y, yaw about z) in the frame of the joint before it (the base for the first), and the
// axis it turns about or slides along, in its own frame.
struct ChainJoint {
  enum class Type : std::uint8_t { revolute, prismatic };
  Type type = Type::revolute;
  Vec3 xyz{}, rpy{};
  Vec3 axis{0, 0, 1};
};

struct ChainSpec {
  std::vector<ChainJoint> joints;  // base to tip
  Vec3 tip_xyz{}, tip_rpy{};       // the tool point in the last joint's frame
};

// Forward kinematics, velocity and Jacobian-transpose statics of a chain. Every buffer is
// sized by the constructor: fk(), velocity() and joint_torques() neither allocate nor throw.
class ChainKinematics {
 public:
  // Throws std::invalid_argument for an empty chain, more than 8 joints, or an axis that is
  // not a direction (zero or not finite).
  explicit ChainKinematics(const ChainSpec& spec);
  ~ChainKinematics();
  ChainKinematics(const ChainKinematics&) = delete;
  ChainKinematics& operator=(const ChainKinematics&) = delete;

  std::size_t joints() const noexcept { return joints_; }
  // The tool point's pose in the base frame; q holds joints() values.
  Pose fk(std::span<const double> q) noexcept;
  // Its twist: J(q)·q̇ (linear velocity of the tool point, angular velocity).
  Twist velocity(std::span<const double> q, std::span<const double> qd) noexcept;
  // The joint torques (forces for prismatic joints) that apply `w` at the tool point: τ = Jᵀ·w,
  // with w's torque taken about the tool point, both in the base frame.
  void joint_torques(std::span<const double> q, const Wrench& w, std::span<double> tau) noexcept;

 private:
  struct Kdl;
  std::size_t joints_ = 0;
  std::unique_ptr<Kdl> kdl_;
};

}  // namespace saw::canopen
