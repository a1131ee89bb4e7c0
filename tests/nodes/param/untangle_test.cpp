#include "nodes/param/untangle.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "nodes/cloud/knn.h"
#include "nodes/param/check.h"
#include "tests/nodes/param/param_test_util.h"

namespace scallop {
namespace {

struct Grid {
  PointCloud cloud;
  Neighborhoods nb;
  std::vector<Eigen::Vector2d> uv;
  std::vector<int> border;  // points on the edge of the square
};

// A jittered 20 x 20 mm grid, 0.5 mm apart, mapped by the identity uv = xy.
// fold(g, x, y) mirrors the map within 1.2 mm of (x, y) about the line u = x: it folds there.
Grid grid() {
  Grid g;
  g.cloud = test::jittered_grid(20, 20, 0.5, 0.5, 0.2, 5);
  g.nb = compute_knn(g.cloud.points, 12);
  for (std::size_t i = 0; i < g.cloud.size(); ++i) {
    const Eigen::Vector3d& p = g.cloud.points[i];
    g.uv.emplace_back(p.x(), p.y());
    if (p.x() < 0.3 || p.x() > 19.7 || p.y() < 0.3 || p.y() > 19.7) g.border.push_back(static_cast<int>(i));
  }
  return g;
}

void fold(Grid& g, double x, double y) {
  for (std::size_t i = 0; i < g.cloud.size(); ++i)
    if ((g.cloud.points[i].head<2>() - Eigen::Vector2d(x, y)).norm() < 1.2) g.uv[i].x() = 2 * x - g.uv[i].x();
}

TEST(Untangle, ALocalFoldIsUntangledAndTheBorderStays) {
  Grid g = grid();
  // Two small mirrored patches: the map folds there.
  fold(g, 7, 7);
  fold(g, 13, 12);
  const std::size_t before = check_map(g.cloud.points, g.cloud.normals, g.nb, g.uv).foldovers;
  ASSERT_GT(before, 0u);
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, {}, {}, 10, 50);
  EXPECT_EQ(r.folded_before, before);
  EXPECT_EQ(r.folded_after, 0u);
  EXPECT_EQ(check_map(g.cloud.points, g.cloud.normals, g.nb, r.uv).foldovers, 0u);
  EXPECT_GT(r.moved, 0u);
  EXPECT_LT(r.moved, 200u);  // local: the rest of the 1681 points keep their place
  EXPECT_GE(r.rounds, 1);
  for (int i : g.border) EXPECT_EQ(r.uv[i], g.uv[i]);
  // the mirrored points come back near where the identity map has them
  for (std::size_t i = 0; i < g.cloud.size(); ++i) EXPECT_LT((r.uv[i] - g.cloud.points[i].head<2>()).norm(), 0.5);
}

// The outer loop of the grid in counter-clockwise order, and the positions of its 4 corners.
std::vector<int> ordered_border(const Grid& g, std::vector<int>& corners) {
  std::vector<std::pair<double, int>> keyed;
  for (int i : g.border) {
    const Eigen::Vector3d& p = g.cloud.points[i];
    // arc length along the square's edge from (0, 0), counter-clockwise
    double s = p.y() < 0.3 ? p.x() : p.x() > 19.7 ? 20 + p.y() : p.y() > 19.7 ? 60 - p.x() : 80 - p.y();
    keyed.emplace_back(s, i);
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<int> loop;
  corners.clear();
  for (const auto& [s, i] : keyed) {
    if (std::abs(s - std::round(s / 20) * 20) < 1e-9) corners.push_back(static_cast<int>(loop.size()));
    loop.push_back(i);
  }
  return loop;
}

TEST(Untangle, OuterLoopPointsSlideAlongTheEdge) {
  Grid g = grid();
  std::vector<int> corners;
  const std::vector<int> loop = ordered_border(g, corners);
  ASSERT_EQ(corners.size(), 4u);
  // A patch on the bottom edge mirrored: the loop runs backwards there and the map folds.
  fold(g, 10, 0);
  const int a = loop[19], b = loop[21];
  ASSERT_GT(g.uv[a].x(), g.uv[b].x());
  ASSERT_GT(check_map(g.cloud.points, g.cloud.normals, g.nb, g.uv).foldovers, 0u);
  auto to_edge = [](const Eigen::Vector2d& q) {  // the bottom edge is all this test needs
    return Eigen::Vector2d(std::clamp(q.x(), 0.0, 20.0), 0.0);
  };
  // held in place, the loop points cannot undo it
  const UntangleResult held = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, loop, corners, {}, 10, 50);
  EXPECT_GT(held.folded_after, 0u);
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, loop, corners, to_edge, 10, 50);
  EXPECT_EQ(r.folded_after, 0u);
  EXPECT_EQ(r.uv[a].y(), 0.0);  // still on the edge
  EXPECT_EQ(r.uv[b].y(), 0.0);
  EXPECT_LT(r.uv[a].x(), r.uv[b].x());  // and in loop order again
  for (int k : corners) EXPECT_EQ(r.uv[loop[k]], g.uv[loop[k]]);
}

TEST(Untangle, WhatTheRoundsCannotMendIsNeverLeftWorse) {
  // The map turned half round within 1.63 mm of the top left corner, the loop held in place:
  // relaxing the points inside cannot undo it, and ten rounds of it left 10 fold-overs of 8 (a
  // scanned bunny cut at 65 degrees: 29 of 8). The map returned is the best any round left, the
  // input's if none did better.
  Grid g = grid();
  std::vector<int> corners;
  const std::vector<int> loop = ordered_border(g, corners);
  const Eigen::Vector2d centre(0.48, 19.31);
  for (std::size_t i = 0; i < g.cloud.size(); ++i)
    if ((g.cloud.points[i].head<2>() - centre).norm() < 1.63) g.uv[i] = 2 * centre - g.uv[i];
  const std::size_t before = check_map(g.cloud.points, g.cloud.normals, g.nb, g.uv).foldovers;
  ASSERT_GT(before, 0u);
  for (int rounds : {1, 3, 10}) {
    const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, loop, corners, {}, rounds, 50);
    EXPECT_EQ(r.folded_before, before);
    EXPECT_LE(r.folded_after, before) << rounds << " rounds";
    EXPECT_EQ(check_map(g.cloud.points, g.cloud.normals, g.nb, r.uv).foldovers, r.folded_after);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < g.uv.size(); ++i) moved += r.uv[i] != g.uv[i];
    EXPECT_EQ(r.moved, moved);
    if (r.folded_after == before) {
      EXPECT_EQ(r.moved, 0u);
    }
  }
}

TEST(Untangle, AnUnfoldedMapIsLeftAlone) {
  const Grid g = grid();
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, {}, {}, 10, 50);
  EXPECT_EQ(r.folded_before, 0u);
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.rounds, 0);
  EXPECT_EQ(r.uv, g.uv);
}

TEST(Untangle, AMapThatFoldsEverywhereIsNotRepaired) {
  Grid g = grid();
  for (auto& q : g.uv) q.x() = -q.x();  // a mirror: every point folds
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, {}, {}, 10, 50);
  EXPECT_EQ(r.folded_before, g.cloud.size());
  EXPECT_EQ(r.folded_after, g.cloud.size());
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.uv, g.uv);
}

TEST(Untangle, Errors) {
  Grid g = grid();
  fold(g, 7, 7);
  try {
    untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, {-1}, {}, {}, 10, 50);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "an outer loop index (-1) is outside the cloud");
  }
  g.uv.pop_back();
  EXPECT_THROW(untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, {}, {}, {}, 10, 50), std::invalid_argument);
}

}  // namespace
}  // namespace scallop

namespace scallop {
namespace {

TEST(Untangle, DomainEdgeIsTheNearestPointOfTheBoundary) {
  UVMap disk;
  disk.domain = "disk";
  disk.radius = 2;
  const auto on_circle = domain_edge(disk);
  EXPECT_NEAR((on_circle({0.3, 0.4}) - Eigen::Vector2d(1.2, 1.6)).norm(), 0, 1e-15);
  EXPECT_NEAR((on_circle({3, 4}) - Eigen::Vector2d(1.2, 1.6)).norm(), 0, 1e-15);
  UVMap rect;
  rect.domain = "rectangle";
  rect.width = 10;
  rect.height = 4;
  const auto on_side = domain_edge(rect);
  EXPECT_EQ(on_side({5, 1}), Eigen::Vector2d(5, 0));
  EXPECT_EQ(on_side({9, 2}), Eigen::Vector2d(10, 2));
  EXPECT_EQ(on_side({1, 3.5}), Eigen::Vector2d(1, 4));
  EXPECT_EQ(on_side({-1, 2}), Eigen::Vector2d(0, 2));
  UVMap other;
  EXPECT_FALSE(domain_edge(other));
}

}  // namespace
}  // namespace scallop
