#include "nodes/geom/grid_knn_2d.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>

namespace scallop {
namespace {

// The k nearest by brute force, nearest first, equal distances by index.
void brute_force(const std::vector<Eigen::Vector2d>& P, const Eigen::Vector2d& q, int k, std::vector<std::uint32_t>& idx,
                 std::vector<double>& sq) {
  std::vector<std::uint32_t> all(P.size());
  std::iota(all.begin(), all.end(), 0u);
  auto d = [&](std::uint32_t i) { return (P[i] - q).squaredNorm(); };
  std::sort(all.begin(), all.end(), [&](auto a, auto b) { return d(a) < d(b) || (d(a) == d(b) && a < b); });
  all.resize(std::min<std::size_t>(std::size_t(k), P.size()));
  idx = all;
  sq.clear();
  for (auto i : idx) sq.push_back(d(i));
}

void expect_exact(const std::vector<Eigen::Vector2d>& P, const std::vector<Eigen::Vector2d>& queries, int k) {
  const GridKnn2d grid(P);
  std::vector<std::uint32_t> idx, want_idx;
  std::vector<double> sq, want_sq;
  for (const auto& q : queries) {
    grid.query(q, k, idx, sq);
    brute_force(P, q, k, want_idx, want_sq);
    ASSERT_EQ(idx, want_idx) << "query (" << q.x() << ", " << q.y() << "), k = " << k;
    ASSERT_EQ(sq, want_sq);
  }
}

TEST(GridKnn2d, FindsTheSameNeighboursAsBruteForce) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector2d> P(3000), queries(400);
  for (auto& p : P) p = {100 * u(rng), 40 * u(rng)};
  // queries inside, on the points themselves, and outside the points' box
  for (std::size_t i = 0; i < queries.size(); ++i)
    queries[i] = i % 4 == 0 ? P[i] : Eigen::Vector2d(-20 + 140 * u(rng), -10 + 60 * u(rng));
  for (int k : {1, 6, 21, 64}) expect_exact(P, queries, k);
}

TEST(GridKnn2d, OverThreeDPointsSearchesTheirXyAlone) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<Eigen::Vector3d> P(2000);
  std::vector<Eigen::Vector2d> xy;
  for (auto& p : P) p = {50 * u(rng), 30 * u(rng), 1e3 * (u(rng) - 0.5)}, xy.push_back(p.head<2>());
  const GridKnn2d over_3d(P), over_xy(xy);
  std::vector<std::uint32_t> idx, want_idx;
  std::vector<double> sq, want_sq;
  for (const Eigen::Vector2d q : {Eigen::Vector2d(25, 15), Eigen::Vector2d(0, 0), Eigen::Vector2d(-9, 40)}) {
    over_3d.query(q, 21, idx, sq);
    over_xy.query(q, 21, want_idx, want_sq);
    EXPECT_EQ(idx, want_idx);
    EXPECT_EQ(sq, want_sq);
  }
}

TEST(GridKnn2d, DenseClustersSparseGapsLinesAndTies) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0, 1);
  std::vector<Eigen::Vector2d> P;
  for (int i = 0; i < 1500; ++i) P.push_back({0.01 * g(rng), 0.01 * g(rng)});  // a dense cluster
  for (int i = 0; i < 50; ++i) P.push_back({50 + g(rng), 30 + g(rng)});       // a far one
  for (int i = 0; i < 20; ++i) P.push_back({5.0 * i, 0});                        // a line, equal gaps
  for (int i = 0; i < 10; ++i) P.push_back({7, 7});                              // repeated points
  std::vector<Eigen::Vector2d> queries{{0, 0}, {25, 15}, {7, 7}, {2.5, 0}, {100, 0}, {-1e3, 1e3}, {50, 30}, {1e300, -1e300}};
  for (int k : {1, 10, 21, 64}) expect_exact(P, queries, k);
  // all points on one line: the grid stays small and exact
  std::vector<Eigen::Vector2d> line;
  for (int i = 0; i < 2000; ++i) line.push_back({0.5 * i, 3});
  expect_exact(line, {{10.2, 3}, {10.25, 4}, {-5, 3}, {2000, 0}}, 21);
}

TEST(GridKnn2d, FewerPointsThanAskedForGivesThemAll) {
  const std::vector<Eigen::Vector2d> P{{0, 0}, {1, 0}, {0, 2}};
  const GridKnn2d grid(P);
  std::vector<std::uint32_t> idx;
  std::vector<double> sq;
  grid.query({0.9, 0.1}, 21, idx, sq);
  EXPECT_EQ(idx, (std::vector<std::uint32_t>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(sq[0], 0.01 + 0.01);
}

TEST(GridKnn2d, BadInput) {
  EXPECT_THROW(GridKnn2d(std::vector<Eigen::Vector2d>{}), std::invalid_argument);
  EXPECT_THROW(GridKnn2d(std::vector<Eigen::Vector2d>{{0, 0}, {NAN, 1}}), std::invalid_argument);
  const GridKnn2d grid(std::vector<Eigen::Vector2d>{{0, 0}});
  std::vector<std::uint32_t> idx;
  std::vector<double> sq;
  grid.query({3, 4}, 5, idx, sq);  // one point, repeated or alone: one cell
  EXPECT_EQ(idx, std::vector<std::uint32_t>{0});
  EXPECT_EQ(sq, std::vector<double>{25});
  EXPECT_THROW(grid.query({0, 0}, 0, idx, sq), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
