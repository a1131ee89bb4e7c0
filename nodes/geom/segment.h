// The nearest point of a segment to a point, and the distance between them: shared by the mesh
// nodes (snapping, feature share), the planners' chord checks and the simulations.
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace scallop {

// The point of [a, b] nearest q (a when the segment is a point).
inline Eigen::Vector3d closest_on_segment(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d e = b - a;
  const double ee = e.squaredNorm();
  const double t = ee > 0 ? std::clamp((q - a).dot(e) / ee, 0.0, 1.0) : 0.0;
  return a + t * e;
}

// Distance from q to the segment [a, b].
inline double segment_distance(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return (closest_on_segment(q, a, b) - q).norm();
}

}  // namespace scallop
