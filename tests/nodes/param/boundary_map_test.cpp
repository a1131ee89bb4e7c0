#include "nodes/param/boundary_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

// A closed polygon sampled unevenly: the square [0,20]^2 with 3 points on the bottom side,
// 7 on the right, 5 on the top, 9 on the left (counter-clockwise).
std::vector<Eigen::Vector3d> uneven_square() {
  std::vector<Eigen::Vector3d> P;
  auto side = [&](Eigen::Vector3d a, Eigen::Vector3d b, int n) {
    for (int i = 0; i < n; ++i) P.push_back(a + (b - a) * (double(i) / n));
  };
  side({0, 0, 0}, {20, 0, 0}, 3);
  side({20, 0, 0}, {20, 20, 0}, 7);
  side({20, 20, 0}, {0, 20, 0}, 5);
  side({0, 20, 0}, {0, 0, 0}, 9);
  return P;
}

std::vector<int> iota_loop(std::size_t n) {
  std::vector<int> l(n);
  for (std::size_t i = 0; i < n; ++i) l[i] = static_cast<int>(i);
  return l;
}

TEST(BoundaryMap, DiskByChordLength) {
  auto P = uneven_square();
  auto loop = iota_loop(P.size());
  UVMap m = map_boundary(P, loop, BoundaryDomain::Disk);
  EXPECT_EQ(m.domain, "disk");
  EXPECT_NEAR(m.radius, 80 / (2 * std::numbers::pi), 1e-12);
  ASSERT_EQ(m.boundary_uv.size(), P.size());
  EXPECT_TRUE(m.uv.empty());
  double s = 0;
  for (std::size_t i = 0; i < P.size(); ++i) {
    EXPECT_NEAR(m.boundary_uv[i].norm(), m.radius, 1e-12);
    double th = std::atan2(m.boundary_uv[i].y(), m.boundary_uv[i].x());
    if (th < -1e-12) th += 2 * std::numbers::pi;
    EXPECT_NEAR(th, 2 * std::numbers::pi * s / 80, 1e-12) << i;
    s += (P[(i + 1) % P.size()] - P[i]).norm();
  }
}

TEST(BoundaryMap, RectangleSidesByChordLength) {
  auto P = uneven_square();
  // Stretch x by 2: sides 40, 20, 40, 20.
  for (auto& p : P) p.x() *= 2;
  auto loop = iota_loop(P.size());
  UVMap m = map_boundary(P, loop, BoundaryDomain::Rectangle);
  EXPECT_EQ(m.domain, "rectangle");
  EXPECT_EQ(m.corners, (std::vector<int>{0, 3, 10, 15}));
  EXPECT_NEAR(m.width, 40, 1e-12);
  EXPECT_NEAR(m.height, 20, 1e-12);
  for (std::size_t i = 0; i < P.size(); ++i) EXPECT_LT((m.boundary_uv[i] - P[i].head<2>()).norm(), 1e-12) << i;
}

TEST(BoundaryMap, ExplicitCornersAndUnequalSides) {
  auto P = uneven_square();
  auto loop = iota_loop(P.size());
  // Corners at positions 1, 3, 10, 15: side 1 is 20 - 6.67, side 4 is 20 + 6.67.
  UVMap m = map_boundary(P, loop, BoundaryDomain::Rectangle, parse_corners("15, 1,3,10", P.size()));
  EXPECT_EQ(m.corners, (std::vector<int>{1, 3, 10, 15}));
  EXPECT_NEAR(m.width, (40.0 / 3 + 20) / 2, 1e-12);
  EXPECT_NEAR(m.height, (20 + 20 + 20.0 / 3) / 2, 1e-12);
  EXPECT_LT((m.boundary_uv[1] - Eigen::Vector2d(0, 0)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[3] - Eigen::Vector2d(m.width, 0)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[10] - Eigen::Vector2d(m.width, m.height)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[15] - Eigen::Vector2d(0, m.height)).norm(), 1e-12);
  // Position 0 lies on side 4 (15 -> 1, wrapping), 20/3 of its 80/3 mm from the end.
  EXPECT_NEAR(m.boundary_uv[0].x(), 0, 1e-12);
  EXPECT_NEAR(m.boundary_uv[0].y(), m.height * (20.0 / 3) / (80.0 / 3), 1e-12);
}

TEST(BoundaryMap, CornersOfANoisySquarePatchAreItsCorners) {
  // A jittered 20 x 20 grid (spacing 0.4): the detected corners are the 4 corner points.
  PointCloud c = test::jittered_grid(20, 20, 0.4, 0.4, 0.5, 21);
  auto nb = compute_knn(c.points, 12);
  auto is_b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, is_b);
  ASSERT_EQ(loops.size(), 1u);
  UVMap m = map_boundary(c.points, loops[0], BoundaryDomain::Rectangle);
  ASSERT_EQ(m.corners.size(), 4u);
  std::vector<Eigen::Vector2d> want = {{0, 0}, {20, 0}, {20, 20}, {0, 20}};
  for (const auto& w : want) {
    double best = 1e9;
    for (int pos : m.corners) best = std::min(best, (c.points[loops[0][pos]].head<2>() - w).norm());
    EXPECT_LT(best, 0.6) << "corner " << w.transpose();
  }
  EXPECT_NEAR(m.width, 20, 1.0);
  EXPECT_NEAR(m.height, 20, 1.0);
}

TEST(BoundaryMap, Errors) {
  auto P = uneven_square();
  auto loop = iota_loop(P.size());
  try {
    parse_corners("1,2,3", P.size());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "corners must be 4 comma-separated integers \"i,j,k,l\", got \"1,2,3\"");
  }
  try {
    parse_corners("1,2,3,24", P.size());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "corner 24 is outside the outer loop's positions 0..23");
  }
  EXPECT_THROW(parse_corners("1,2,2,5", P.size()), std::invalid_argument);
  EXPECT_THROW(parse_corners("1,2,x,5", P.size()), std::invalid_argument);
  EXPECT_TRUE(parse_corners("  ", P.size()).empty());
  EXPECT_THROW(map_boundary(P, {0, 1}, BoundaryDomain::Disk), std::invalid_argument);
  EXPECT_THROW(map_boundary(P, {0, 1, 99}, BoundaryDomain::Disk), std::invalid_argument);
  EXPECT_THROW(parse_boundary_domain("square"), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
