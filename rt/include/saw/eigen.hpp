// Conversions between the Plain CRTK vectors (saw::Vec3) and Eigen, for component code.
#pragma once

#include <Eigen/Core>

#include "saw/crtk.hpp"

namespace saw {

inline Eigen::Vector3d to_eigen(const Vec3& v) { return {v[0], v[1], v[2]}; }
inline Vec3 to_vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace saw
