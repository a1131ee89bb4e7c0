// The normal equations of the small weighted least-squares fits (quadrics in two variables) that
// the height-field model and the (u,v) interpolation solve at every query.
#pragma once

#include <Eigen/Core>

namespace scallop {

// M += w b b^T, lower triangle only (M's upper triangle is left as it was). Written out, as the
// fits call it for each of their 20 to 64 neighbours: Eigen's selfadjoint rank update is an
// out-of-line call per neighbour (6 % of the bundled example's CPU; written out, the example
// takes 0.98 times the CPU, the same products in the same order, outputs byte-identical).
template <int N>
inline void add_weighted_outer_lower(Eigen::Matrix<double, N, N>& M, const Eigen::Matrix<double, N, 1>& b, double w) {
  for (int c = 0; c < N; ++c) {
    const double wb = w * b[c];
    for (int r = c; r < N; ++r) M(r, c) += wb * b[r];
  }
}

}  // namespace scallop
