#include "nodes/geom/normal_equations.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace scallop {
namespace {

// The normal equations of a weighted quadric fit over n places (x, y), lower triangle only, as
// the fits build them.
Eigen::Matrix<double, 6, 6> quadric_normal_equations(const std::vector<Eigen::Vector2d>& xy) {
  Eigen::Matrix<double, 6, 6> M = Eigen::Matrix<double, 6, 6>::Zero();
  for (const auto& q : xy) {
    Eigen::Matrix<double, 6, 1> b;
    b << 1, q.x(), q.y(), q.x() * q.x(), q.x() * q.y(), q.y() * q.y();
    add_weighted_outer_lower(M, b, std::exp(-2 * q.squaredNorm()));
  }
  return M;
}

TEST(NormalEquations, SolvesAQuadricFitAsEigenDoes) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Eigen::Vector2d> xy;
    for (int i = 0; i < 20; ++i) xy.emplace_back(u(rng), u(rng));
    const Eigen::Matrix<double, 6, 6> M = quadric_normal_equations(xy);
    // the upper triangle holds nothing: only the lower may be read
    Eigen::Matrix<double, 6, 6> full = M;
    full.triangularView<Eigen::StrictlyUpper>() = M.transpose();
    Eigen::Matrix<double, 6, 6> B;
    for (int i = 0; i < 36; ++i) B(i) = u(rng);
    Eigen::Matrix<double, 6, 6> X;
    ASSERT_TRUE(solve_positive_definite(M, B, X, 1e-9));
    EXPECT_LT((full * X - B).norm(), 1e-12 * full.norm() * X.norm());
    EXPECT_LT((X - full.ldlt().solve(B)).norm(), 1e-9 * X.norm());
  }
}

TEST(NormalEquations, ADegenerateFitIsRefused) {
  // Places on a line: the quadric's normal equations are singular, the plane's too; off the line
  // the plane's are fine.
  std::vector<Eigen::Vector2d> line;
  for (int i = 0; i < 20; ++i) line.emplace_back(0.05 * i - 0.5, 0.3 * (0.05 * i - 0.5));
  const Eigen::Matrix<double, 6, 6> M = quadric_normal_equations(line);
  const Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Ones();
  Eigen::Matrix<double, 6, 1> x = Eigen::Matrix<double, 6, 1>::Constant(7);
  EXPECT_FALSE(solve_positive_definite(M, b, x, 1e-9));
  EXPECT_EQ(x, (Eigen::Matrix<double, 6, 1>::Constant(7)));  // untouched
  const Eigen::Matrix3d M3 = M.topLeftCorner<3, 3>();
  Eigen::Vector3d x3;
  EXPECT_FALSE(solve_positive_definite(M3, Eigen::Vector3d(1, 1, 1), x3, 1e-9));
  // a matrix that is not positive definite
  Eigen::Matrix2d N;
  N << 1, 0, 2, 1;  // lower triangle: [[1, 2], [2, 1]], eigenvalues 3 and -1
  Eigen::Vector2d y;
  EXPECT_FALSE(solve_positive_definite(N, Eigen::Vector2d(1, 0), y, 0.0));
  // a diagonal one, solved exactly
  Eigen::Matrix2d D = Eigen::Vector2d(4, 0.25).asDiagonal();
  ASSERT_TRUE(solve_positive_definite(D, Eigen::Vector2d(2, 2), y, 1e-3));
  EXPECT_EQ(y, Eigen::Vector2d(0.5, 8));
  EXPECT_FALSE(solve_positive_definite(D, Eigen::Vector2d(2, 2), y, 0.1));  // pivots 1/16 apart
}

}  // namespace
}  // namespace scallop
