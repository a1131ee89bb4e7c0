#include "nodes/mesh/mesh_distance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

TEST(MeshDistance, DistancesRaysAndSidesOfTheUnitCube) {
  const MeshDistance cube(test::cube_mesh(3));
  EXPECT_NEAR(cube(V(0.5, 0.5, 1.7)), 0.7, 1e-12);
  EXPECT_NEAR(cube(V(1.3, 1.4, 0.5)), 0.5, 1e-12);  // to the edge x = y = 1
  EXPECT_NEAR(cube(V(0.5, 0.5, 1.7), V(0.5, 0.5, 1)), 0.7, 1e-12);
  EXPECT_NEAR(cube.ray_distance(V(0.5, 0.5, -2), V(0, 0, 1)), 2, 1e-12);
  EXPECT_TRUE(std::isinf(cube.ray_distance(V(0.5, 0.5, 2), V(0, 0, 1))));
  // Signed: inside below zero, by the nearest face or, at an edge or a corner, by the rays.
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 0.9)), -0.1, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 1.1)), 0.1, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(1.3, 1.4, 0.5)), 0.5, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(2, 2, 2)), std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 0.5)), -0.5, 1e-12);
  EXPECT_TRUE(std::isinf(MeshDistance(Mesh()).signed_distance(V(0, 0, 0))));
}

TEST(MeshDistance, TheClosestFaceIsThePolygonNotItsFannedTriangle) {
  // The unit cube as six quads (face 1 the top z = 1, each fanned into two triangles).
  const Mesh cube = test::unit_cube();
  const MeshDistance d(cube);
  EXPECT_EQ(d.closest_face(V(0.2, 0.7, 1.5)), 1u);
  EXPECT_EQ(d.closest_face(V(0.8, 0.3, 1.5)), 1u);
  EXPECT_EQ(d.closest_face(V(0.5, 0.5, -0.3)), 0u);
  EXPECT_EQ(MeshDistance(Mesh()).closest_face(V(0, 0, 0)), std::numeric_limits<std::size_t>::max());
}

TEST(MeshDistance, TheLeastAlongASegmentIsFoundBetweenItsSamples) {
  const MeshDistance cube(test::cube_mesh(3));
  // Parallel to the edge x = z = 1 at 0.2 from both faces: sqrt(0.08) from y = 0 to 1, more
  // beyond; sampled only every 1.5, the least is found between the samples, to a thousandth of
  // its depth under the floor 1 (more than eps = 1e-6 here).
  V where;
  std::size_t evaluations = 0;
  const double least = cube.least_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, 1, 1e-6, where, evaluations);
  EXPECT_LE(least, std::sqrt(0.08) + 1e-12);
  EXPECT_GE(least, std::sqrt(0.08) - 1e-3 * (1 - std::sqrt(0.08)));
  // With a floor just above it, to eps.
  EXPECT_GE(cube.least_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, std::sqrt(0.08) + 1e-4, 1e-6, where, evaluations),
            std::sqrt(0.08) - 1e-6);
  EXPECT_GE(where.y(), -1e-6);
  EXPECT_LE(where.y(), 1 + 1e-6);
  EXPECT_GT(evaluations, 3u);
  // Through the cube: the centre is 0.5 inside; unsigned, the least is on the faces it crosses.
  EXPECT_NEAR(cube.least_along(V(0.5, 0.5, -1), V(0.5, 0.5, 2), 0.7, 0, 1e-6, where, evaluations), -0.5, 1e-6);
  EXPECT_NEAR(where.z(), 0.5, 1e-3);
  EXPECT_NEAR(cube.least_along(V(0.5, 0.5, -1), V(0.5, 0.5, 2), 0.7, 0.01, 1e-6, where, evaluations, false), 0, 1e-6);
  // Farther than the floor everywhere: a lower bound, no search below it.
  const double far = cube.least_along(V(3, -1, 3), V(3, 2, 3), 0.5, 1, 1e-6, where, evaluations);
  EXPECT_LE(far, 2 * std::sqrt(2.0) + 1e-12);
  EXPECT_GE(far, 1 - 1e-12);
}

}  // namespace
}  // namespace scallop
