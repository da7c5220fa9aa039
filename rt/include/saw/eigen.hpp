// Conversions between the Plain CRTK vectors and rotations (saw::Vec3, saw::Quat) and Eigen, for
// component code.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "saw/crtk.hpp"

namespace saw {

inline Eigen::Vector3d to_eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
inline Vec3 to_vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }
// Quat is x, y, z, w (ROS's order); Eigen's constructor takes w first — the one place that says so.
inline Eigen::Quaterniond to_eigen(const Quat& q) { return {q[3], q[0], q[1], q[2]}; }
inline Quat to_quat(const Eigen::Quaterniond& q) { return {q.x(), q.y(), q.z(), q.w()}; }

// rad/s in the frame both are expressed in: the constant rate that turns `from` into `to` in dt
// (the shorter way; zero when dt is not positive). A simulated device's measured_cv.angular.
inline Eigen::Vector3d angular_velocity(const Eigen::Quaterniond& from, const Eigen::Quaterniond& to,
                                        double dt) {
  if (!(dt > 0)) return Eigen::Vector3d::Zero();
  const Eigen::AngleAxisd turned(to * from.conjugate());
  return turned.axis() * (turned.angle() / dt);
}

}  // namespace saw
