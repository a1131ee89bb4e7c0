#include "nodes/param/laplacian.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "nodes/cloud/knn.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

// A wavy height field with exact normals, so the optimal scheme sees curved neighbourhoods.
PointCloud wavy_cloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 20);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    double x = u(rng), y = u(rng);
    c.points.emplace_back(x, y, 2 * std::sin(x / 3) * std::cos(y / 4));
    Eigen::Vector3d g(-2 / 3.0 * std::cos(x / 3) * std::cos(y / 4), 2 / 4.0 * std::sin(x / 3) * std::sin(y / 4), 1);
    c.normals.push_back(g.normalized());
  }
  return c;
}

TEST(Laplacian, RowsSumToZeroForEveryScheme) {
  PointCloud c = wavy_cloud(1500, 1);
  Neighborhoods nb = compute_knn(c.points, 12);
  for (auto s : {LaplacianScheme::Uniform, LaplacianScheme::Heat, LaplacianScheme::Optimal}) {
    auto L = build_laplacian(c.points, c.normals, nb, s);
    ASSERT_EQ(L.rows(), 1500);
    Eigen::VectorXd rs = L * Eigen::VectorXd::Ones(L.cols());
    EXPECT_LT(rs.cwiseAbs().maxCoeff(), 1e-12) << to_string(s);
    // Diagonal 1 (weights normalised), k off-diagonal entries.
    EXPECT_NEAR(L.coeff(7, 7), 1.0, 1e-12) << to_string(s);
    EXPECT_EQ(L.nonZeros(), 1500 * 13) << to_string(s);
  }
}

TEST(Laplacian, UniformWeightsAreOneOverK) {
  PointCloud c = wavy_cloud(200, 2);
  Neighborhoods nb = compute_knn(c.points, 8);
  auto L = build_laplacian(c.points, {}, nb, LaplacianScheme::Uniform);
  for (int j = 0; j < 8; ++j) EXPECT_DOUBLE_EQ(L.coeff(3, nb.index(3, j)), -1.0 / 8);
}

TEST(Laplacian, HeatKernelWeights) {
  PointCloud c = wavy_cloud(300, 3);
  Neighborhoods nb = compute_knn(c.points, 10);
  const double t = 0.7;
  auto L = build_laplacian(c.points, {}, nb, LaplacianScheme::Heat, t);
  double s = 0;
  for (int j = 0; j < 10; ++j) s += std::exp(-nb.sq_dist(5, j) / t);
  for (int j = 0; j < 10; ++j) EXPECT_NEAR(L.coeff(5, nb.index(5, j)), -std::exp(-nb.sq_dist(5, j) / t) / s, 1e-14);
  // t = 0 means the mean squared neighbour distance.
  auto La = build_laplacian(c.points, {}, nb, LaplacianScheme::Heat, 0);
  auto Lb = build_laplacian(c.points, {}, nb, LaplacianScheme::Heat, mean_sq_neighbor_distance(nb));
  EXPECT_LT((La - Lb).norm(), 1e-15);
}

TEST(Laplacian, OptimalWeightsReproducePlanarPoints) {
  // A tilted plane: sum_j w_ij p_j = p_i at every point whose neighbours surround it.
  PointCloud c = test::random_disk(2000, 10, 4);
  Eigen::Matrix3d R = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  for (auto& p : c.points) p = R * p + Eigen::Vector3d(3, -1, 7);
  for (auto& n : c.normals) n = R * n;
  Neighborhoods nb = compute_knn(c.points, 12);
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  Eigen::MatrixXd P(c.size(), 3);
  for (std::size_t i = 0; i < c.size(); ++i) P.row(i) = c.points[i].transpose();
  Eigen::MatrixXd LP = L * P;  // (L p)_i = p_i - sum_j w_ij p_j
  int checked = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_LT(LP.row(i).norm(), 1e-9) << "point " << i;  // holds at boundary points too
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
  // Linear precision also without normals (local PCA planes).
  auto L2 = build_laplacian(c.points, {}, nb, LaplacianScheme::Optimal);
  EXPECT_LT((L2 * P).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Laplacian, OptimalWeightsSolveTheRegularizedKByKSystem) {
  // The node solves the rank-2 system through its 2 x 2 form; here the k x k system of the
  // header, (C + delta tr(C) I) w = 1 with c_jl = d_j . d_l, is factorised whole, scaled to sum 1
  // and projected onto {sum_j w_j d_j = 0, sum_j w_j = 1} (least change): the same weights.
  PointCloud c = wavy_cloud(800, 6);
  const int k = 12;
  const double delta = 1e-3;
  Neighborhoods nb = compute_knn(c.points, k);
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal, 0, delta);
  double worst = 0;
  for (std::size_t i = 0; i < c.size(); i += 7) {
    const Eigen::Vector3d n = c.normals[i];
    const Eigen::Vector3d t1 = n.unitOrthogonal(), t2 = n.cross(t1);  // any tangent basis
    Eigen::MatrixXd D(2, k);
    for (int j = 0; j < k; ++j) {
      const Eigen::Vector3d d = c.points[i] - c.points[nb.index(i, j)];
      D.col(j) << d.dot(t1), d.dot(t2);
    }
    Eigen::MatrixXd C = D.transpose() * D;
    C.diagonal().array() += delta * C.trace();
    Eigen::VectorXd w = C.ldlt().solve(Eigen::VectorXd::Ones(k));
    w /= w.sum();
    Eigen::MatrixXd A(3, k);
    A.topRows(2) = D;
    A.row(2).setOnes();
    w -= A.transpose() * (A * A.transpose()).ldlt().solve(A * w - Eigen::Vector3d(0, 0, 1));
    for (int j = 0; j < k; ++j) worst = std::max(worst, std::abs(-L.coeff(i, nb.index(i, j)) - w(j)));
  }
  EXPECT_LT(worst, 1e-12);
}

TEST(Laplacian, RowsJoinedBothWaysAverageTheirNeighboursEitherWay) {
  // 0 names 1 and 2; 1 and 2 name only each other; 3 names 0 and 2. Joined with the uniform
  // scheme, row 1 averages 2 and 0 (which names it), row 2 averages 1, 0 and 3; rows 0 and 3 are
  // unchanged.
  const std::vector<Eigen::Vector3d> P = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  Eigen::SparseMatrix<double, Eigen::RowMajor> L(4, 4);
  std::vector<Eigen::Triplet<double>> t = {{0, 0, 1},    {0, 1, -0.25}, {0, 2, -0.75}, {1, 1, 1}, {1, 2, -1},
                                           {2, 2, 1},    {2, 1, -1},    {3, 3, 1},     {3, 0, -0.6}, {3, 2, -0.4}};
  L.setFromTriplets(t.begin(), t.end());
  const Eigen::MatrixXd J = Eigen::MatrixXd(join_rows_both_ways(L, P, {}, LaplacianScheme::Uniform, 1, 1e-3, {1, 2}));
  Eigen::MatrixXd expected(4, 4);
  expected << 1, -0.25, -0.75, 0,  //
      -0.5, 1, -0.5, 0,            //
      -1.0 / 3, -1.0 / 3, 1, -1.0 / 3,  //
      -0.6, 0, -0.4, 1;
  EXPECT_LT((J - expected).cwiseAbs().maxCoeff(), 1e-15) << J;
  EXPECT_THROW(join_rows_both_ways(L, P, {}, LaplacianScheme::Uniform, 1, 1e-3, {4}), std::invalid_argument);
  EXPECT_THROW(join_rows_both_ways(L, {P[0]}, {}, LaplacianScheme::Uniform, 1, 1e-3, {1}), std::invalid_argument);
}

TEST(Laplacian, RowsJoinedWithOptimalWeightsKeepLinearPrecision) {
  // A tight cluster inside a planar disk: its 12 nearest neighbours are its own, and the rows
  // rebuilt over both ways with the optimal scheme still reproduce the points' own positions
  // (sum_j w_ij p_j = p_i on a plane), as every other row does.
  PointCloud c = test::random_disk(600, 10, 21);
  for (int i = 0; i < 16; ++i)
    c.points.emplace_back(3 + 0.04 * (i % 4), -2 + 0.04 * (i / 4), 0), c.normals.push_back(Eigen::Vector3d::UnitZ());
  const auto nb = compute_knn(c.points, 12);
  const auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  std::vector<int> cluster;
  for (int i = 600; i < 616; ++i) cluster.push_back(i);
  const auto J = join_rows_both_ways(L, c.points, c.normals, LaplacianScheme::Optimal, 0, 1e-3, cluster);
  Eigen::MatrixXd X(c.size(), 2);
  for (std::size_t i = 0; i < c.size(); ++i) X.row(i) = c.points[i].head<2>().transpose();
  const Eigen::MatrixXd LX = J * X;
  for (int i : cluster) {
    EXPECT_LT(LX.row(i).norm(), 1e-12) << "row " << i;
    int outside = 0;  // the rebuilt row names points around the cluster
    for (Eigen::SparseMatrix<double, Eigen::RowMajor>::InnerIterator it(J, i); it; ++it) outside += it.col() < 600;
    EXPECT_GT(outside, 0) << "row " << i;
  }
  EXPECT_EQ((Eigen::MatrixXd(J).topRows(600) - Eigen::MatrixXd(L).topRows(600)).cwiseAbs().maxCoeff(), 0.0);
}

TEST(Laplacian, Errors) {
  PointCloud c = wavy_cloud(50, 5);
  Neighborhoods nb2 = compute_knn(c.points, 2);
  try {
    build_laplacian(c.points, c.normals, nb2, LaplacianScheme::Optimal);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the optimal Laplacian needs k >= 3 neighbours per point (k = 2)");
  }
  Neighborhoods nb = compute_knn(c.points, 6);
  std::vector<Eigen::Vector3d> fewer(c.points.begin(), c.points.begin() + 40);
  EXPECT_THROW(build_laplacian(fewer, {}, nb, LaplacianScheme::Uniform), std::invalid_argument);
  EXPECT_THROW(parse_laplacian_scheme("cotan"), std::invalid_argument);
  EXPECT_EQ(parse_laplacian_scheme("heat"), LaplacianScheme::Heat);
}

}  // namespace
}  // namespace scallop
