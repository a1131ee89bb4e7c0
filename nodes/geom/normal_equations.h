// The normal equations of the small weighted least-squares fits (quadrics in two variables) that
// the height-field model and the (u,v) interpolation solve at every query.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace scallop {

// M += w b b^T, lower triangle only (M's upper triangle is left as it was). Written out, as the
// fits call it for each of their 20 to 64 neighbours: Eigen's selfadjoint rank update is an
// out-of-line call per neighbour (6 % of the bundled example's CPU; written out, the example
// takes 0.98 times the CPU, the same products in the same order, outputs byte-identical).
// Unrolled whole (GCC left the inner loop's variable trip count as a loop): each entry's sum
// the same as before, cloud.denoise's graph on the noisy plane 4.11 -> 3.87 s, byte-identical.
template <int N>
inline void add_weighted_outer_lower(Eigen::Matrix<double, N, N>& M, const Eigen::Matrix<double, N, 1>& b, double w) {
#pragma GCC unroll 16
  for (int c = 0; c < N; ++c) {
    const double wb = w * b[c];
#pragma GCC unroll 16
    for (int r = c; r < N; ++r) M(r, c) += wb * b[r];
  }
}

// Solves M X = B by Cholesky, M symmetric positive definite given by its lower triangle (the
// upper is not read). False, X untouched, when a pivot (the squared diagonal of the factor, which
// for these well-scaled bases behaves like an eigenvalue) is not above `min_ratio` times the
// largest, or the result is not finite: a degenerate neighbourhood. Written out for the fits'
// fixed sizes: Eigen's LDLT with a matrix right-hand side goes through its blocked general solver
// and its condition estimate through several more solves.
template <int N, int C>
inline bool solve_positive_definite(const Eigen::Matrix<double, N, N>& M, const Eigen::Matrix<double, N, C>& B,
                                    Eigen::Matrix<double, N, C>& X, double min_ratio) {
  double L[N][N], inv[N];
  double pivot_max = 0, pivot_min = INFINITY;
  for (int j = 0; j < N; ++j) {
    double d = M(j, j);
    for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
    if (!(d > 0)) return false;
    pivot_max = std::max(pivot_max, d);
    pivot_min = std::min(pivot_min, d);
    inv[j] = 1 / std::sqrt(d);
    for (int i = j + 1; i < N; ++i) {
      double s = M(i, j);
      for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
      L[i][j] = s * inv[j];
    }
  }
  if (!(pivot_min > min_ratio * pivot_max)) return false;
  // Row by row with the right-hand sides side by side (they are independent: the inner loops
  // over them vectorise and do not wait on each other).
  double Y[N][C];
  for (int i = 0; i < N; ++i) {  // L y = b
    for (int c = 0; c < C; ++c) Y[i][c] = B(i, c);
    for (int k = 0; k < i; ++k)
      for (int c = 0; c < C; ++c) Y[i][c] -= L[i][k] * Y[k][c];
    for (int c = 0; c < C; ++c) Y[i][c] *= inv[i];
  }
  for (int i = N - 1; i >= 0; --i) {  // L^T x = y
    for (int k = i + 1; k < N; ++k)
      for (int c = 0; c < C; ++c) Y[i][c] -= L[k][i] * Y[k][c];
    for (int c = 0; c < C; ++c) Y[i][c] *= inv[i];
  }
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < C; ++c)
      if (!std::isfinite(Y[i][c])) return false;
  for (int i = 0; i < N; ++i)
    for (int c = 0; c < C; ++c) X(i, c) = Y[i][c];
  return true;
}

}  // namespace scallop
