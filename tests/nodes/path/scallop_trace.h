// The scallop a test measures on its own, the way ../shared/tools/verify.py defines it and
// independently of the planners' ray-capsule test (step_size.h): at a surface point p with unit
// normal n, the smallest t >= 0 with p + t n within r of a ball-centre segment, by sphere tracing.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <vector>

namespace scallop::test {

using Segment = std::array<Eigen::Vector3d, 2>;

inline double segment_distance(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double t = ab.squaredNorm() > 0 ? std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
  return (q - (a + t * ab)).norm();
}

// Past `limit` (mm) the tracing stops: the place counts as left `limit` high or more.
inline double traced_scallop(const Eigen::Vector3d& p, const Eigen::Vector3d& n, const std::vector<Segment>& centres,
                             double r, double limit = 1) {
  double t = 0;
  for (int it = 0; it < 200; ++it) {
    double d = 1e9;
    for (const auto& s : centres) d = std::min(d, segment_distance(p + t * n, s[0], s[1]));
    if (d - r <= 1e-9) break;
    t += d - r;
    if (t > limit) break;
  }
  return t;
}

}  // namespace scallop::test
