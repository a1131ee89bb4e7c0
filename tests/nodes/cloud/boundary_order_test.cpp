#include "nodes/cloud/boundary_order.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "nodes/cloud/boundary.h"
#include "nodes/cloud/knn.h"
#include "nodes/geom/best_fit_plane.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

const double kPi = std::numbers::pi;

// The loops of a flat cloud (normals +z), its boundary points found as cloud.boundary finds them.
std::vector<std::vector<int>> loops_of(const PointCloud& c, int k) {
  auto nb = compute_knn(c.points, k);
  return order_boundary_loops(c.points, c.normals, nb, detect_boundary(c.points, c.normals, nb, kPi / 2));
}

// n random points on the plate [0, 40] x [0, 30] at z = 0, those `keep` accepts.
template <class Keep>
PointCloud random_plate(std::size_t n, unsigned seed, Keep keep) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(0, 40), uy(0, 30);
  PointCloud c;
  while (c.size() < n) {
    const Eigen::Vector3d p(ux(rng), uy(rng), 0);
    if (!keep(p)) continue;
    c.points.push_back(p);
    c.normals.push_back(Eigen::Vector3d::UnitZ());
  }
  return c;
}

// The signed area a loop of the plate encloses, seen from +z.
double plate_area(const PointCloud& c, const std::vector<int>& loop) {
  return projected_loop_area(c.points, loop, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
}

TEST(BoundaryOrder, NoisyCircleIsOneLoopInAngularOrder) {
  // 400 points on a circle of radius 10, unevenly spaced (angles random) and with 0.1 mm radial
  // noise, plus the inside; all boundary flags given.
  std::mt19937 rng(51);
  std::uniform_real_distribution<double> ua(0, 2 * kPi);
  std::normal_distribution<double> noise(0, 0.1);
  PointCloud c = test::random_disk(1500, 9.5, 52);
  std::vector<std::uint8_t> flags(c.size(), 0);
  for (int i = 0; i < 400; ++i) {
    double a = ua(rng), r = 10 + noise(rng);
    c.points.emplace_back(r * std::cos(a), r * std::sin(a), 0);
    c.normals.push_back(Eigen::Vector3d::UnitZ());
    flags.push_back(1);
  }
  auto nb = compute_knn(c.points, 12);
  auto loops = order_boundary_loops(c.points, c.normals, nb, flags);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_GE(loops[0].size(), 390u);
  // Counter-clockwise: winding +1, and no step goes back by more than the noise allows.
  double winding = 0, worst = 0;
  for (std::size_t i = 0; i < loops[0].size(); ++i) {
    const auto& p = c.points[loops[0][i]];
    const auto& q = c.points[loops[0][(i + 1) % loops[0].size()]];
    double d = std::remainder(std::atan2(q.y(), q.x()) - std::atan2(p.y(), p.x()), 2 * kPi);
    winding += d;
    worst = std::min(worst, d);
  }
  EXPECT_NEAR(winding, 2 * kPi, 1e-9);
  EXPECT_GT(worst, -0.02);  // 0.2 mm of backtracking at most
}

TEST(BoundaryOrder, PatchWithAHoleGivesTwoLoopsOuterFirst) {
  // Jittered 30 x 20 grid with a round hole of radius 4 at (12, 10).
  PointCloud g = test::jittered_grid(30, 20, 0.4, 0.4, 0.5, 53);
  PointCloud c;
  for (std::size_t i = 0; i < g.size(); ++i)
    if ((g.points[i].head<2>() - Eigen::Vector2d(12, 10)).norm() > 4) {
      c.points.push_back(g.points[i]);
      c.normals.push_back(g.normals[i]);
    }
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, kPi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, b);
  ASSERT_EQ(loops.size(), 2u);
  Eigen::Vector3d c0, n0;
  best_fit_plane(c.points, c.normals, c0, n0);
  EXPECT_GT(n0.z(), 0.99);
  double outer = projected_loop_area(c.points, loops[0], c0, n0);
  double hole = projected_loop_area(c.points, loops[1], c0, n0);
  EXPECT_NEAR(outer, 600, 30);             // counter-clockwise
  // The hole's boundary points are the grid points just outside radius 4 (spacing 0.4).
  EXPECT_NEAR(hole, -kPi * 4.2 * 4.2, 0.1 * kPi * 16);  // clockwise
  for (int i : loops[1]) EXPECT_NEAR((c.points[i].head<2>() - Eigen::Vector2d(12, 10)).norm(), 4.2, 0.6);
}

TEST(BoundaryOrder, AHoleNearTheOutlineIsALoopOfItsOwn) {
  // A scan's random points (8 a mm^2, as 50 000 on the catalog's plane) on a 40 x 30 plate with
  // a round hole of radius 4 whose edge is 2 mm from the plate's: the rims' boundary points are
  // closer across the bridge than two neighbourhood radii, and a link across it had made the
  // two loops one.
  const Eigen::Vector2d centre(34, 15);
  const PointCloud c = random_plate(9600, 56, [&](const Eigen::Vector3d& p) { return (p.head<2>() - centre).norm() > 4; });
  auto loops = loops_of(c, 16);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_NEAR(plate_area(c, loops[0]), 1200, 60);
  EXPECT_NEAR(plate_area(c, loops[1]), -kPi * 16, 0.15 * kPi * 16);
  for (int i : loops[1]) {  // the rim's band of boundary points
    EXPECT_GT((c.points[i].head<2>() - centre).norm(), 4.0);
    EXPECT_LT((c.points[i].head<2>() - centre).norm(), 5.0);
  }
  // and the outline goes round the bridge, not into the hole
  for (int i : loops[0]) EXPECT_GT((c.points[i].head<2>() - centre).norm(), 5.0);
}

TEST(BoundaryOrder, AGapInTheOutlinesBoundaryPointsIsStillBridged) {
  // The same plate without the hole, its boundary points missing along 1.6 mm of two opposite
  // sides (wider than a neighbourhood radius): the outline's two pieces, which do not close by
  // themselves, are joined across the gaps.
  const PointCloud c = random_plate(9600, 57, [](const Eigen::Vector3d&) { return true; });
  auto nb = compute_knn(c.points, 16);
  auto b = detect_boundary(c.points, c.normals, nb, kPi / 2);
  int cleared = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (b[i] && c.points[i].x() > 20 && c.points[i].x() < 21.6 && std::abs(c.points[i].y() - 15) > 13)
      b[i] = 0, ++cleared;
  ASSERT_GE(cleared, 4);
  auto loops = order_boundary_loops(c.points, c.normals, nb, b);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_NEAR(plate_area(c, loops[0]), 1200, 60);
}

// The plate with a slit 1.2 mm wide down from its top edge to y = slit_bottom, and its boundary
// points missing along 2.5 mm of the top edge further right (x 22 to 24.5): one loop, round the
// plate less the slit, through the top edge's boundary points between the slit and the gap.
void expect_one_loop_along_the_top_edge_past_a_slit(unsigned seed, double slit_bottom) {
  const PointCloud c = random_plate(9600, seed, [&](const Eigen::Vector3d& p) {
    return !(std::abs(p.x() - 10) < 0.6 && p.y() > slit_bottom);
  });
  auto nb = compute_knn(c.points, 16);
  auto b = detect_boundary(c.points, c.normals, nb, kPi / 2);
  for (std::size_t i = 0; i < c.size(); ++i)
    if (b[i] && c.points[i].x() > 22 && c.points[i].x() < 24.5 && c.points[i].y() > 28) b[i] = 0;
  auto loops = order_boundary_loops(c.points, c.normals, nb, b);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_NEAR(plate_area(c, loops[0]), 1200 - 1.2 * (30 - slit_bottom), 60);
  std::vector<char> on_loop(c.size(), 0);
  for (int i : loops[0]) on_loop[i] = 1;
  int stretch = 0, kept = 0;
  for (std::size_t i = 0; i < c.size(); ++i)
    if (b[i] && c.points[i].x() > 12 && c.points[i].x() < 21 && c.points[i].y() > 29.5) ++stretch, kept += on_loop[i];
  ASSERT_GT(stretch, 10);
  EXPECT_GE(kept, stretch - 2);
}

TEST(BoundaryOrder, AStretchHangingOffTheTreeIsPartOfTheLoop) {
  // The links across the slit's mouth make a junction there, and the top edge between the slit
  // and the gap hangs off the tree's longest path (which runs down the slit and round): it was
  // left out as a spur (0 of its 19 points), and the loop cut across the plate from the slit's
  // mouth to the gap.
  expect_one_loop_along_the_top_edge_past_a_slit(1, 12);
}

TEST(BoundaryOrder, AStretchCutOffByGapsAtBothEndsIsPartOfTheLoop) {
  // Another scan: the top edge between the slit's mouth and the gap is linked to neither, a tree
  // of its own whose tour runs along it and back. It enclosed nearly nothing and was dropped as a
  // sampling void (none of its 33 points on the loop); it is spliced in.
  expect_one_loop_along_the_top_edge_past_a_slit(7, 18);
}

TEST(BoundaryOrder, NonConvexOutline) {
  // A C-shaped patch: [0,20]^2 minus the notch [6,20] x [7,13]. The loop follows the notch.
  PointCloud g = test::jittered_grid(20, 20, 0.4, 0.4, 0.4, 54);
  PointCloud c;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const auto& p = g.points[i];
    if (p.x() > 6 && p.y() > 7 && p.y() < 13) continue;
    c.points.push_back(p);
    c.normals.push_back(g.normals[i]);
  }
  auto nb = compute_knn(c.points, 12);
  auto b = detect_boundary(c.points, c.normals, nb, kPi / 2);
  auto loops = order_boundary_loops(c.points, c.normals, nb, b);
  ASSERT_EQ(loops.size(), 1u);
  double len = 0, step = 0;
  for (std::size_t i = 0; i < loops[0].size(); ++i) {
    double s = (c.points[loops[0][i]] - c.points[loops[0][(i + 1) % loops[0].size()]]).norm();
    len += s;
    step = std::max(step, s);
  }
  EXPECT_LT(step, 1.2);                 // no shortcut across the notch (6 mm wide)
  EXPECT_NEAR(len, 80 + 2 * 14, 12);    // outline length 108, plus some zig-zag
}

TEST(BoundaryOrder, ClosedCloudIsAClearError) {
  PointCloud c = test::random_disk(200, 10, 55);
  auto nb = compute_knn(c.points, 8);
  std::vector<std::uint8_t> none(c.size(), 0);
  try {
    order_boundary_loops(c.points, c.normals, nb, none);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "no boundary points found: the cloud looks closed (a 3-axis finishing path needs an open patch)");
  }
  std::vector<std::uint8_t> few(c.size(), 0);
  for (int i = 0; i < 5; ++i) few[i] = 1;
  EXPECT_THROW(order_boundary_loops(c.points, c.normals, nb, few), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
