// InstrumentKinematics: a PSM-like instrument arm about a remote centre of motion, forward and inverse.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <string_view>

namespace saw::drivers {

// The da Vinci PSM's structure (the dVRK's published PSM and Large Needle Driver): the shaft
// turns about a remote centre of motion (the base frame's origin, the cannula's pivot) by the
// outer yaw (about x) and pitch (about y), slides along itself (insertion, the distance from the
// pivot to the wrist's pitch axis; the shaft along −z with every joint at zero), rolls about
// itself, and ends in a wrist: pitch (about x), then 9.1 mm further yaw (about y), then 10.2 mm
// to the tip between the jaws. With every joint at zero the tip's frame is the base's. Every
// buffer is sized in the constructor: fk(), jacobian() and ik() allocate nothing.
class InstrumentKinematics {
 public:
  static constexpr int dof = 6;
  using Joints = Eigen::Matrix<double, dof, 1>;
  static constexpr double wrist_pitch_to_yaw = 0.0091, wrist_yaw_to_tip = 0.0102;  // m

  InstrumentKinematics();
  ~InstrumentKinematics();
  InstrumentKinematics(const InstrumentKinematics&) = delete;
  InstrumentKinematics& operator=(const InstrumentKinematics&) = delete;

  static std::array<std::string_view, dof> joint_names() noexcept;
  Eigen::Isometry3d fk(const Joints& q) noexcept;
  // The Jacobian at the tip in the base's frame: rows linear (0–2), then angular (3–5).
  Eigen::Matrix<double, 6, dof> jacobian(const Joints& q) noexcept;
  // Joints reaching `goal`, from `q` (the seed, replaced by the answer) by damped least squares,
  // each step within [min, max]: true once within 1 µm and 1e-5 rad, false (q the closest
  // found) after `iterations`.
  bool ik(const Eigen::Isometry3d& goal, const Joints& min, const Joints& max, Joints& q,
          int iterations = 30) noexcept;

 private:
  struct Kdl;
  std::unique_ptr<Kdl> kdl_;
};

}  // namespace saw::drivers
