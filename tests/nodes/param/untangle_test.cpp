#include "nodes/param/untangle.h"

#include <gtest/gtest.h>

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
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, 10, 50);
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

TEST(Untangle, AnUnfoldedMapIsLeftAlone) {
  const Grid g = grid();
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, 10, 50);
  EXPECT_EQ(r.folded_before, 0u);
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.rounds, 0);
  EXPECT_EQ(r.uv, g.uv);
}

TEST(Untangle, AMapThatFoldsEverywhereIsNotRepaired) {
  Grid g = grid();
  for (auto& q : g.uv) q.x() = -q.x();  // a mirror: every point folds
  const UntangleResult r = untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, g.border, 10, 50);
  EXPECT_EQ(r.folded_before, g.cloud.size());
  EXPECT_EQ(r.folded_after, g.cloud.size());
  EXPECT_EQ(r.moved, 0u);
  EXPECT_EQ(r.uv, g.uv);
}

TEST(Untangle, Errors) {
  Grid g = grid();
  fold(g, 7, 7);
  try {
    untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, {-1}, 10, 50);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "an outer loop index (-1) is outside the cloud");
  }
  g.uv.pop_back();
  EXPECT_THROW(untangle_map(g.cloud.points, g.cloud.normals, g.nb, g.uv, {}, 10, 50), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
