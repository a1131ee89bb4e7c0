// Orthonormal tangent frame of a unit normal, shared by the meshless parameterisation steps.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace scallop {

// n  unit normal. Returns t1, t2 with (t1, t2, n) a right-handed orthonormal frame, so that
// angles measured from t1 towards t2 are counter-clockwise seen from the side n points to.
inline void tangent_frame(const Eigen::Vector3d& n, Eigen::Vector3d& t1, Eigen::Vector3d& t2) {
  // Cross with the axis least aligned with n: never degenerate.
  Eigen::Vector3d a = std::abs(n.x()) < 0.6 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  t1 = a.cross(n).normalized();
  t2 = n.cross(t1);
}

}  // namespace scallop
