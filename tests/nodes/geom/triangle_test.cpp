#include "nodes/geom/triangle.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// The triangle (0,0,0), (2,0,0), (0,2,0): each region of its plane answered in closed form.
TEST(ClosestOnTriangle, EachRegionOfTheTrianglesPlaneHasItsNearestPoint) {
  const V a(0, 0, 0), b(2, 0, 0), c(0, 2, 0);
  auto near = [&](const V& q) { return closest_on_triangle(q, a, b, c); };
  EXPECT_TRUE(near(V(0.5, 0.5, 3)).isApprox(V(0.5, 0.5, 0)));       // over the inside
  EXPECT_TRUE(near(V(-1, -2, 1)).isApprox(a));                      // beyond corner a
  EXPECT_TRUE(near(V(3, -0.5, -1)).isApprox(b));                    // beyond corner b
  EXPECT_TRUE(near(V(-0.1, 5, 0)).isApprox(c));                     // beyond corner c
  EXPECT_TRUE(near(V(1.2, -3, 2)).isApprox(V(1.2, 0, 0)));          // beyond edge ab
  EXPECT_TRUE(near(V(-4, 0.7, 0)).isApprox(V(0, 0.7, 0)));          // beyond edge ca
  EXPECT_TRUE(near(V(2, 2, 1)).isApprox(V(1, 1, 0)));               // beyond edge bc, at its middle
  EXPECT_TRUE(near(V(0.25, 0.25, -0.5)).isApprox(V(0.25, 0.25, 0)));  // under the inside
}

TEST(ClosestOnTriangle, ATriangleWithNoAreaIsItsEdges) {
  // Corners on one line (c between a and b), and all three equal.
  EXPECT_TRUE(closest_on_triangle(V(1, 1, 0), V(0, 0, 0), V(2, 0, 0), V(1.5, 0, 0)).isApprox(V(1, 0, 0)));
  EXPECT_TRUE(closest_on_triangle(V(3, 1, 0), V(0, 0, 0), V(2, 0, 0), V(1.5, 0, 0)).isApprox(V(2, 0, 0)));
  EXPECT_TRUE(closest_on_triangle(V(1, 2, 3), V(1, 1, 1), V(1, 1, 1), V(1, 1, 1)).isApprox(V(1, 1, 1)));
}

// Against the nearest of a fine sampling of the triangle: never farther than the samples, and
// within their spacing of the nearest sample.
TEST(ClosestOnTriangle, NoPointOfTheTriangleIsNearer) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int trial = 0; trial < 200; ++trial) {
    const V a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)), q(u(rng), u(rng), u(rng));
    const V p = closest_on_triangle(q, a, b, c);
    // p lies on the triangle: its barycentric coordinates are in [0, 1].
    const V n = (b - a).cross(c - a);
    EXPECT_NEAR((p - a).dot(n), 0, 1e-9 * n.norm());
    double best = 1e300;
    const int N = 200;
    for (int i = 0; i <= N; ++i)
      for (int j = 0; i + j <= N; ++j) best = std::min(best, (a + (b - a) * (double(i) / N) + (c - a) * (double(j) / N) - q).norm());
    EXPECT_LE((p - q).norm(), best + 1e-12);
    EXPECT_GE((p - q).norm(), best - 4.0 * ((b - a).norm() + (c - a).norm()) / N);
  }
}

}  // namespace
}  // namespace scallop
