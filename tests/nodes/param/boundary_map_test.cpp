#include "nodes/param/boundary_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

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
  UVMap m = map_boundary(P, loop, BoundaryDomain::Disk, {}, 0);  // the exact polygon, unsmoothed
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
  UVMap m = map_boundary(P, loop, BoundaryDomain::Rectangle, {}, 0);
  EXPECT_EQ(m.domain, "rectangle");
  EXPECT_EQ(m.corners, (std::vector<int>{0, 3, 10, 15}));
  EXPECT_NEAR(m.width, 40, 1e-12);
  EXPECT_NEAR(m.height, 20, 1e-12);
  for (std::size_t i = 0; i < P.size(); ++i) EXPECT_LT((m.boundary_uv[i] - P[i].head<2>()).norm(), 1e-12) << i;
}

TEST(BoundaryMap, ExplicitCornersAndUnequalSides) {
  auto P = uneven_square();
  auto loop = iota_loop(P.size());
  // Corners at positions 1, 3, 10, 15: side 1 is 20 - 6.67, side 4 is 20 + 6.67. Sides 2 and 4
  // (20 and 26.67) are the longer pair, so they go along u: corner 15 at the origin.
  UVMap m = map_boundary(P, loop, BoundaryDomain::Rectangle, parse_corners("15, 1,3,10", P.size()), 0);
  EXPECT_EQ(m.corners, (std::vector<int>{1, 3, 10, 15}));
  EXPECT_NEAR(m.width, (20 + 20 + 20.0 / 3) / 2, 1e-12);
  EXPECT_NEAR(m.height, (40.0 / 3 + 20) / 2, 1e-12);
  EXPECT_LT((m.boundary_uv[15] - Eigen::Vector2d(0, 0)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[1] - Eigen::Vector2d(m.width, 0)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[3] - Eigen::Vector2d(m.width, m.height)).norm(), 1e-12);
  EXPECT_LT((m.boundary_uv[10] - Eigen::Vector2d(0, m.height)).norm(), 1e-12);
  // Position 0 lies on side 4 (15 -> 1, wrapping), 20/3 of its 80/3 mm from the end.
  EXPECT_NEAR(m.boundary_uv[0].x(), m.width * (60.0 / 3) / (80.0 / 3), 1e-12);
  EXPECT_NEAR(m.boundary_uv[0].y(), 0, 1e-12);
  // Corners at 0, 5, 10, 15: sides 1 and 3 (25.71 and 20) are the longer pair, as they come:
  // corner 0 at the origin.
  UVMap n = map_boundary(P, loop, BoundaryDomain::Rectangle, parse_corners("0,5,10,15", P.size()), 0);
  EXPECT_NEAR(n.width, (20 + 40.0 / 7 + 20) / 2, 1e-12);
  EXPECT_NEAR(n.height, (100.0 / 7 + 20) / 2, 1e-12);
  EXPECT_LT((n.boundary_uv[0] - Eigen::Vector2d(0, 0)).norm(), 1e-12);
  EXPECT_LT((n.boundary_uv[5] - Eigen::Vector2d(n.width, 0)).norm(), 1e-12);
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

TEST(BoundaryMap, SmoothedLoopIsAMovingAverage) {
  std::vector<Eigen::Vector3d> P = {{0, 0, 0}, {1, 1, 0}, {2, 0, 0}, {3, 1, 0}, {4, 0, 0}, {5, 1, 0}, {6, 0, 0}};
  std::vector<int> loop = iota_loop(P.size());
  auto Q = smoothed_loop(P, loop, 1);
  ASSERT_EQ(Q.size(), P.size());
  EXPECT_LT((Q[3] - Eigen::Vector3d(3, 1.0 / 3, 0)).norm(), 1e-12);
  EXPECT_LT((Q[0] - (P[6] + P[0] + P[1]) / 3).norm(), 1e-12);  // wraps around the closed loop
  auto Q0 = smoothed_loop(P, loop, 0);
  for (std::size_t i = 0; i < P.size(); ++i) EXPECT_EQ(Q0[i], P[i]);
  // The window never exceeds the loop: w = (7 - 1) / 2 = 3 averages every point.
  auto Qall = smoothed_loop(P, loop, 50);
  for (const auto& q : Qall) EXPECT_LT((q - Eigen::Vector3d(3, 3.0 / 7, 0)).norm(), 1e-12);
}

TEST(BoundaryMap, RandomSquarePatchHasItsTrueSize) {
  // Uniform random points on a 40 x 30 rectangle (spacing ~0.3 mm): the detected boundary is a
  // band a point or two thick and the ordered loop zig-zags through it (its raw chord length is
  // ~15 % too long); the chord length of the smoothed loop gives W, H within 3 % of the true
  // sides. (It runs short by about two spacings per side: the band lies a little inside the
  // edge and the smoothing rounds the corners.)
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> ux(0, 40), uy(0, 30);
  PointCloud c;
  for (int i = 0; i < 12000; ++i) c.points.emplace_back(ux(rng), uy(rng), 0.0);
  c.normals.assign(c.size(), Eigen::Vector3d::UnitZ());
  auto nb = compute_knn(c.points, 16);
  auto is_b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, is_b);
  ASSERT_EQ(loops.size(), 1u);
  UVMap m = map_boundary(c.points, loops[0], BoundaryDomain::Rectangle);
  UVMap raw = map_boundary(c.points, loops[0], BoundaryDomain::Rectangle, {}, 0);
  double w = std::max(m.width, m.height), h = std::min(m.width, m.height);
  std::printf("[ random 40 x 30 ] W %.2f H %.2f; unsmoothed perimeter %.1f (true 140)\n", w, h,
              2 * (raw.width + raw.height));
  EXPECT_NEAR(w, 40, 0.03 * 40);
  EXPECT_NEAR(h, 30, 0.03 * 30);
  EXPECT_GT(2 * (raw.width + raw.height), 1.05 * 140);  // the zig-zag the smoothing removes
  UVMap d = map_boundary(c.points, loops[0], BoundaryDomain::Disk);
  EXPECT_NEAR(d.radius, 140 / (2 * std::numbers::pi), 0.03 * 140 / (2 * std::numbers::pi));
}

TEST(BoundaryMap, NotchIsNoCorner) {
  // A 30 x 20 rectangle with a deep V-notch in its top side: the notch turns more sharply than
  // the corners, but it turns the wrong way (reflex), so the 4 corners are the rectangle's.
  std::vector<Eigen::Vector3d> P;
  auto side = [&](Eigen::Vector3d a, Eigen::Vector3d b, int n) {
    for (int i = 0; i < n; ++i) P.push_back(a + (b - a) * (double(i) / n));
  };
  side({0, 0, 0}, {30, 0, 0}, 60);
  side({30, 0, 0}, {30, 20, 0}, 40);
  side({30, 20, 0}, {16, 20, 0}, 28);
  side({16, 20, 0}, {15, 8, 0}, 24);
  side({15, 8, 0}, {14, 20, 0}, 24);
  side({14, 20, 0}, {0, 20, 0}, 28);
  side({0, 20, 0}, {0, 0, 0}, 40);
  auto corners = detect_corners(P, iota_loop(P.size()));
  std::vector<Eigen::Vector2d> want = {{0, 0}, {30, 0}, {30, 20}, {0, 20}};
  for (const auto& w : want) {
    double best = 1e9;
    for (int pos : corners) best = std::min(best, (P[pos].head<2>() - w).norm());
    EXPECT_LT(best, 1.0) << "corner " << w.transpose();
  }
}

TEST(BoundaryMap, BandPointsAreProjectedAndOffsetInward) {
  // A flat random rectangle: every band point gets a value inside the domain, at its depth
  // inside the band's outer envelope (slope (1, 0): isometric), on the side it projects to.
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(0, 30), uy(0, 20);
  PointCloud c;
  for (int i = 0; i < 3000; ++i) c.points.emplace_back(ux(rng), uy(rng), 0.0);
  c.normals.assign(c.size(), Eigen::Vector3d::UnitZ());
  auto nb = compute_knn(c.points, 16);
  auto is_b = detect_boundary(c.points, c.normals, nb, std::numbers::pi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, is_b);
  UVMap m = map_boundary(c.points, loops[0], BoundaryDomain::Rectangle);
  auto band = outer_band(c.points, c.normals, is_b, loops, loops[0]);
  std::size_t fixed = 0, probes = 0;
  for (const auto& b : band) {
    EXPECT_GE(b.depth, 0);
    (b.fixed ? fixed : probes)++;
  }
  EXPECT_GE(fixed, loops[0].size());
  EXPECT_GT(probes, fixed);
  auto values = band_values(band, m);
  EXPECT_GE(values.size(), loops[0].size() * 9 / 10);
  for (const auto& [i, uv] : values) {
    EXPECT_GE(uv.x(), -1e-9);
    EXPECT_GE(uv.y(), -1e-9);
    EXPECT_LE(uv.x(), m.width + 1e-9);
    EXPECT_LE(uv.y(), m.height + 1e-9);
    // Near the edge of the domain, as the point is near the edge of the patch (2 mm).
    double edge = std::min({uv.x(), uv.y(), m.width - uv.x(), m.height - uv.y()});
    EXPECT_LT(edge, 2.0) << i;
  }
  // The slope measured on the map of a flat patch is close to isometric.
  auto L = build_laplacian(c.points, c.normals, nb, LaplacianScheme::Optimal);
  std::vector<Eigen::Vector2d> zero(loops[0].size(), Eigen::Vector2d::Zero());
  auto first = solve_harmonic(L, m, HarmonicSolver::Direct, band_values(band, m, zero));
  auto slope = band_depth_slope(band, m, first.uv);
  std::vector<double> a;
  for (const auto& s : slope) a.push_back(s.x());
  std::sort(a.begin(), a.end());
  EXPECT_NEAR(a[a.size() / 2], 1.0, 0.15);
  EXPECT_THROW(band_values(band, m, std::vector<Eigen::Vector2d>(3)), std::invalid_argument);
  EXPECT_THROW(outer_band(c.points, c.normals, std::vector<std::uint8_t>(5), loops, loops[0]), std::invalid_argument);
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
