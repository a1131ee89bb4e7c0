#include "nodes/geom/spatial_order.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace scallop {
namespace {

TEST(SpatialOrder, TheCornersOfACubeInMortonOrder) {
  // Z-order interleaves x (lowest bit), y, z: the corner (x, y, z) in {0,1}^3 is number x + 2y + 4z.
  std::vector<Eigen::Vector3d> P;
  for (int code : {5, 3, 0, 7, 6, 1, 4, 2}) P.emplace_back(code & 1, (code >> 1) & 1, (code >> 2) & 1);
  const std::vector<std::size_t> order = spatial_order(P);
  ASSERT_EQ(order.size(), 8u);
  for (int r = 0; r < 8; ++r) {
    const Eigen::Vector3d& p = P[order[r]];
    EXPECT_EQ(p.x() + 2 * p.y() + 4 * p.z(), r);
  }
}

TEST(SpatialOrder, APermutationThatKeepsNeighboursNear) {
  // Random points of a 100 x 100 square: in their given order consecutive points are ~52 mm
  // apart on average; along the curve they are a few times the spacing (~0.3 mm) apart.
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 100);
  std::vector<Eigen::Vector3d> P(100000);
  for (auto& p : P) p = Eigen::Vector3d(u(rng), u(rng), 0.01 * u(rng));
  const std::vector<std::size_t> order = spatial_order(P);
  std::vector<std::size_t> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) ASSERT_EQ(sorted[i], i);
  double before = 0, after = 0;
  for (std::size_t i = 1; i < P.size(); ++i) {
    before += (P[i] - P[i - 1]).norm();
    after += (P[order[i]] - P[order[i - 1]]).norm();
  }
  before /= P.size() - 1;
  after /= P.size() - 1;
  EXPECT_GT(before, 40);
  EXPECT_LT(after, 1.5);
}

TEST(SpatialOrder, CoincidentAndEmptyClouds) {
  EXPECT_TRUE(spatial_order({}).empty());
  const std::vector<Eigen::Vector3d> same(4, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(spatial_order(same), (std::vector<std::size_t>{0, 1, 2, 3}));  // ties by index
}

}  // namespace
}  // namespace scallop
