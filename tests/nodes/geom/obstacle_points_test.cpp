#include "nodes/geom/obstacle_points.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace scallop {
namespace {

using Eigen::Vector3d;

// A floor z = 0 over [-6, 4] x [-6, 6], every 0.25 mm: the patch that is machined.
std::vector<Vector3d> floor_points() {
  std::vector<Vector3d> P;
  for (double x = -6; x <= 4 + 1e-9; x += 0.25)
    for (double y = -6; y <= 6 + 1e-9; y += 0.25) P.emplace_back(x, y, 0);
  return P;
}

TEST(ObstaclePoints, AWallBesideTheFloorIsOneApartFromItsFoot) {
  const auto floor = floor_points();
  HeightFieldModel patch(floor);
  const double apart = 3 * patch.spacing();
  std::vector<Vector3d> wall;
  for (double z = 0.25; z <= 6 + 1e-9; z += 0.25)
    for (double y = -6; y <= 6 + 1e-9; y += 0.25) wall.emplace_back(4.2, y, z);
  const auto obstacles = obstacle_points(wall, patch);
  ASSERT_FALSE(obstacles.empty());
  std::size_t expect = 0;
  for (const auto& q : wall) {
    // the nearest floor point is on its edge x = 4, at q's y
    const double d = std::hypot(0.2, q.z());
    expect += d > apart && q.z() > 0.1 * d;
  }
  EXPECT_EQ(obstacles.size(), expect);
  for (const auto& q : obstacles) EXPECT_GT(std::hypot(0.2, q.z()), apart);
}

TEST(ObstaclePoints, AConvexRimCutOffByTheTrimIsNoObstacleCleanOrNoisy) {
  // The floor continued past x = 4 as a cylinder of radius 10 falling away (a convex rim the trim
  // cut off), clean and with noise of 0.02 mm: it bends away below the floor, or lies within the
  // noise of it: none of it is an obstacle.
  const auto floor = floor_points();
  HeightFieldModel patch(floor);
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0, 0.02);
  for (double sigma : {0.0, 1.0}) {
    std::vector<Vector3d> rim;
    for (double a = 0.02; a <= std::numbers::pi / 2; a += 0.02)
      for (double y = -6; y <= 6 + 1e-9; y += 0.25)
        rim.emplace_back(4 + 10 * std::sin(a) + sigma * noise(rng), y + sigma * noise(rng),
                         10 * std::cos(a) - 10 + sigma * noise(rng));
    EXPECT_TRUE(obstacle_points(rim, patch).empty()) << sigma;
  }
}

}  // namespace
}  // namespace scallop
