#include "nodes/geom/outline.h"

#include <gtest/gtest.h>

#include <cmath>

using namespace scallop;

namespace {

// The square [0, 10]² traced by points 0.5 apart (as a cloud's boundary loop comes), with a
// hole [4, 6]².
Outline square_with_hole() {
  std::vector<Eigen::Vector2d> outer;
  for (int i = 0; i < 20; ++i) outer.emplace_back(0.5 * i, 0);
  for (int i = 0; i < 20; ++i) outer.emplace_back(10, 0.5 * i);
  for (int i = 20; i > 0; --i) outer.emplace_back(0.5 * i, 10);
  for (int i = 20; i > 0; --i) outer.emplace_back(0, 0.5 * i);
  return Outline({outer, {{4, 4}, {6, 4}, {6, 6}, {4, 6}}});
}

}  // namespace

TEST(Outline, ContainsByTheEvenOddRule) {
  const Outline o = square_with_hole();
  EXPECT_TRUE(o.contains({1, 1}));
  EXPECT_FALSE(o.contains({5, 5}));  // in the hole
  EXPECT_FALSE(o.contains({11, 5}));
  EXPECT_TRUE(o.any_contains({5, 5}));
}

// How far a place lies off the patch: 0 on it, else the exact distance to the nearest loop's
// edges, beyond the outer loop (beside an edge, and from a corner) or inside the hole.
TEST(Outline, BeyondIsTheDistanceOffThePatch) {
  const Outline o = square_with_hole();
  EXPECT_EQ(o.beyond({1, 1}), 0.0);
  EXPECT_EQ(o.beyond({3.8, 5}), 0.0);  // between the outer loop and the hole
  EXPECT_NEAR(o.beyond({10.7, 3.25}), 0.7, 1e-12);
  EXPECT_NEAR(o.beyond({4.1, -1.5}), 1.5, 1e-12);
  EXPECT_NEAR(o.beyond({-0.3, 10.4}), std::hypot(0.3, 0.4), 1e-12);
  EXPECT_NEAR(o.beyond({13, 14}), 5.0, 1e-12);
  EXPECT_NEAR(o.beyond({5, 5}), 1.0, 1e-12);  // in the hole
  EXPECT_NEAR(o.beyond({4.3, 5.2}), 0.3, 1e-12);
  EXPECT_NEAR(o.beyond({4.1, 4.2}), 0.1, 1e-12);
  EXPECT_EQ(o.beyond({6.1, 5}), 0.0);
  for (double x = -0.95; x < 11; x += 0.1)
    for (double y = -0.95; y < 11; y += 0.1) EXPECT_EQ(o.beyond({x, y}) == 0.0, o.contains({x, y})) << x << " " << y;
  const Outline none;
  EXPECT_TRUE(std::isinf(none.beyond({0, 0})));
}

// The distance to the nearest loop's edges, on the patch as off it (a raster's strip beside the
// outline asks it on the patch).
TEST(Outline, EdgeDistanceIsTheDistanceToTheNearestEdgeOnEitherSide) {
  const Outline o = square_with_hole();
  EXPECT_NEAR(o.edge_distance({1, 2}), 1.0, 1e-12);
  EXPECT_NEAR(o.edge_distance({3.8, 5}), 0.2, 1e-12);  // beside the hole, on the patch
  EXPECT_NEAR(o.edge_distance({5, 5}), 1.0, 1e-12);    // in the hole
  EXPECT_NEAR(o.edge_distance({10.7, 3.25}), 0.7, 1e-12);
  EXPECT_NEAR(o.edge_distance({-0.3, 10.4}), std::hypot(0.3, 0.4), 1e-12);
  for (double x = -0.95; x < 11; x += 0.1)
    for (double y = -0.95; y < 11; y += 0.1)
      if (!o.contains({x, y})) EXPECT_EQ(o.edge_distance({x, y}), o.beyond({x, y})) << x << " " << y;
  EXPECT_TRUE(std::isinf(Outline().edge_distance({0, 0})));
}

// A hole's loop may run either way round, and the loops come in any order: what is a hole is
// what an odd number of the others contain.
TEST(Outline, BeyondTellsTheHoleByTheEvenOddRuleWhicheverWayItsLoopRuns) {
  const std::vector<Eigen::Vector2d> outer{{0, 0}, {10, 0}, {10, 10}, {0, 10}};
  const std::vector<Eigen::Vector2d> hole{{4, 4}, {4, 6}, {6, 6}, {6, 4}};  // clockwise
  const std::vector<Eigen::Vector2d> island{{4.5, 4.5}, {5.5, 4.5}, {5.5, 5.5}, {4.5, 5.5}};  // in the hole
  const Outline o({hole, island, outer});
  EXPECT_EQ(o.beyond({1, 1}), 0.0);
  EXPECT_NEAR(o.beyond({4.2, 5}), 0.2, 1e-12);  // in the hole
  EXPECT_EQ(o.beyond({5, 5}), 0.0);              // on the island
  EXPECT_NEAR(o.beyond({-1, 5}), 1.0, 1e-12);
}

// Inside or out from the nearest edge's side, at a reflex corner and a convex one too: an L of
// [0, 10]² less [5, 10]², clockwise (the side follows the loop's orientation).
TEST(Outline, BeyondAnLShapedLoopAtItsReflexCorner) {
  const Outline o({{{0, 0}, {0, 10}, {5, 10}, {5, 5}, {10, 5}, {10, 0}}});
  EXPECT_EQ(o.beyond({4.9, 4.9}), 0.0);   // inside, nearest the reflex corner (5, 5)
  EXPECT_EQ(o.beyond({4.5, 5.5}), 0.0);   // inside, nearest the edge x = 5
  EXPECT_NEAR(o.beyond({5.3, 5.4}), 0.3, 1e-12);  // in the notch, beside the edge x = 5
  EXPECT_EQ(o.beyond({5.3, 4.9}), 0.0);  // below the notch: inside
  EXPECT_NEAR(o.beyond({7, 5.2}), 0.2, 1e-12);
  EXPECT_NEAR(o.beyond({10.3, -0.4}), 0.5, 1e-12);  // beyond the convex corner (10, 0)
  EXPECT_EQ(o.beyond({9.9, 0.1}), 0.0);
  for (double x = 0.25; x < 10; x += 0.5)
    for (double y = 0.25; y < 10; y += 0.5)
      EXPECT_EQ(o.beyond({x, y}) == 0.0, o.contains({x, y})) << x << " " << y;
}
