// The nearest point of a segment to a point, and the distance between them: shared by the mesh
// nodes (snapping, feature share), the planners' chord checks and the simulations; and the
// nearest points of two segments (a move against a triangle's edge, nodes/geom/triangle.h).
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

// The nearest points of the segments [p1, q1] and [p2, q2]: c1 on the first, c2 on the second
// (Ericson, Real-Time Collision Detection, 5.1.9); returns their squared distance. Parallel
// segments (or nearly: the determinant under 1e-12 of its scale) and segments that are points
// get one of their nearest pairs.
inline double closest_between_segments(const Eigen::Vector3d& p1, const Eigen::Vector3d& q1, const Eigen::Vector3d& p2,
                                       const Eigen::Vector3d& q2, Eigen::Vector3d& c1, Eigen::Vector3d& c2) {
  const Eigen::Vector3d d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a > 0 && e > 0) {
    const double b = d1.dot(d2), c = d1.dot(r), denom = a * e - b * b;
    s = denom > 1e-12 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    t = (b * s + f) / e;
    if (t < 0)
      t = 0, s = std::clamp(-c / a, 0.0, 1.0);
    else if (t > 1)
      t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
  } else if (a > 0) {
    s = std::clamp(-d1.dot(r) / a, 0.0, 1.0);
  } else if (e > 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  }
  c1 = p1 + s * d1, c2 = p2 + t * d2;
  return (c1 - c2).squaredNorm();
}

}  // namespace scallop
