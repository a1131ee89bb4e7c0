// The least clearance of a ball moved straight from a to b: the least of distance(c) - r over its
// centres c, marched by that value itself. A distance to a set (or a signed distance to a solid)
// cannot fall faster than c moves, so no lower value hides between the steps by more than
// tol / 2. Shared by the certificates' rapid checks (post.simulate against the cloud's points,
// post.simulate_part against the part's mesh), as verify.py and verify_part.py check rapids.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace scallop {

// distance  callable Eigen::Vector3d -> double (mm); tol > 0. `at`, when given, gets the centre
// of the least.
template <class Distance>
double least_clearance_along(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r, double tol,
                             const Distance& distance, Eigen::Vector3d* at = nullptr) {
  const double L = (b - a).norm();
  double least = INFINITY, t = 0;
  for (;;) {
    const Eigen::Vector3d c = L > 0 ? Eigen::Vector3d(a + (b - a) * (t / L)) : a;
    const double clear = distance(c) - r;
    if (clear < least) {
      least = clear;
      if (at) *at = c;
    }
    if (t >= L) break;
    t = std::min(L, t + std::max(std::abs(clear), 0.5 * tol));
  }
  return least;
}

}  // namespace scallop
