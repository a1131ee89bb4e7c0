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

// Two segments in closed form: skew lines crossing inside both, the nearest pair past an end,
// parallel ones side by side, and a segment that is a point.
TEST(ClosestBetweenSegments, ClosedForms) {
  V c1, c2;
  // The x axis from -1 to 1 and the line y = 0.5 ... along z at height 2: 2 apart at (0.5, 0, 0).
  EXPECT_NEAR(closest_between_segments(V(-1, 0, 0), V(1, 0, 0), V(0.5, -1, 2), V(0.5, 1, 2), c1, c2), 4, 1e-12);
  EXPECT_TRUE(c1.isApprox(V(0.5, 0, 0)));
  EXPECT_TRUE(c2.isApprox(V(0.5, 0, 2)));
  // The second moved to x = 3: past the first's end b = (1, 0, 0), sqrt(4 + 4) away.
  EXPECT_NEAR(closest_between_segments(V(-1, 0, 0), V(1, 0, 0), V(3, -1, 2), V(3, 1, 2), c1, c2), 8, 1e-12);
  EXPECT_TRUE(c1.isApprox(V(1, 0, 0)));
  // Parallel, overlapping along x, 0.3 apart.
  EXPECT_NEAR(closest_between_segments(V(0, 0, 0), V(2, 0, 0), V(1, 0.3, 0), V(5, 0.3, 0), c1, c2), 0.09, 1e-12);
  EXPECT_NEAR((c1 - c2).norm(), 0.3, 1e-12);
  // A point against a segment.
  EXPECT_NEAR(closest_between_segments(V(1, 1, 0), V(1, 1, 0), V(0, 0, 0), V(2, 0, 0), c1, c2), 1, 1e-12);
  EXPECT_TRUE(c2.isApprox(V(1, 0, 0)));
}

// The nearest pair of a segment and a triangle against fine sampling of both: on random pairs
// (crossing, apart, nearly parallel to the plane, in it) never farther than the samples' least,
// within their spacing of it, the two points on their sets, and 0 exactly where they cross.
TEST(ClosestSegmentTriangle, NoPairOfPointsIsNearer) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2, 2);
  const V t0(0, 0, 0), t1(2, 0, 0), t2(0, 2, 0);
  V s, t;
  // Closed forms: through the inside; over it, parallel; beside edge t1-t2; in the plane across it.
  EXPECT_EQ(closest_segment_triangle(V(0.5, 0.5, -1), V(0.5, 0.5, 1), t0, t1, t2, s, t), 0);
  EXPECT_TRUE(s.isApprox(V(0.5, 0.5, 0)));
  EXPECT_NEAR(closest_segment_triangle(V(-5, 0.5, 0.7), V(5, 0.5, 0.7), t0, t1, t2, s, t), 0.49, 1e-12);
  EXPECT_NEAR(closest_segment_triangle(V(2, 2, -1), V(2, 2, 1), t0, t1, t2, s, t), 2, 1e-12);  // to (1, 1, 0)
  EXPECT_TRUE(t.isApprox(V(1, 1, 0)));
  EXPECT_NEAR(closest_segment_triangle(V(-1, 0.5, 0), V(3, 0.5, 0), t0, t1, t2, s, t), 0, 1e-15);
  for (int trial = 0; trial < 300; ++trial) {
    const V a(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)), e(u(rng), u(rng), u(rng));
    V p(u(rng), u(rng), u(rng)), q(u(rng), u(rng), u(rng));
    const V n = (c - a).cross(e - a).normalized();
    if (trial % 3 == 1) q = p + (q - p) - ((q - p).dot(n) - 1e-4 * u(rng)) * n;  // nearly parallel to the plane
    if (trial % 3 == 2) p -= (p - a).dot(n) * n, q -= (q - a).dot(n) * n;          // in the plane
    const double d = std::sqrt(closest_segment_triangle(p, q, a, c, e, s, t));
    EXPECT_NEAR((s - t).norm(), d, 1e-12);
    EXPECT_NEAR(segment_distance(s, p, q), 0, 1e-9);
    EXPECT_NEAR((closest_on_triangle(t, a, c, e) - t).norm(), 0, 1e-9);
    const int N = 60, M = 200;
    double best = 1e300;
    for (int k = 0; k <= M; ++k) {
      const V x = p + (q - p) * (double(k) / M);
      for (int i = 0; i <= N; ++i)
        for (int j = 0; i + j <= N; ++j) best = std::min(best, (a + (c - a) * (double(i) / N) + (e - a) * (double(j) / N) - x).norm());
    }
    EXPECT_LE(d, best + 1e-12) << trial;
    EXPECT_GE(d, best - 4.0 * ((c - a).norm() + (e - a).norm()) / N - 2 * (q - p).norm() / M) << trial;
  }
}

// A ball moving onto a point: straight at it, 0.6 aside (the 0.8 of the rest of r), past it, away.
TEST(BallTouchPoint, ClosedForms) {
  const V down(0, 0, -1);
  EXPECT_NEAR(ball_touch_point(V(0, 0, 10), down, 1, V(0, 0, 0)), 9, 1e-12);
  EXPECT_NEAR(ball_touch_point(V(0.6, 0, 10), down, 1, V(0, 0, 0)), 9.2, 1e-12);
  EXPECT_TRUE(std::isinf(ball_touch_point(V(1.2, 0, 10), down, 1, V(0, 0, 0))));
  EXPECT_TRUE(std::isinf(ball_touch_point(V(0, 0, 10), V(0, 0, 1), 1, V(0, 0, 0))));
}

// A ball moving onto a triangle, in closed form: straight down onto the inside, onto an edge and
// a corner from beside them, and one that passes by.
TEST(BallTouchTriangle, ClosedForms) {
  const V t0(0, 0, 0), t1(2, 0, 0), t2(0, 2, 0), down(0, 0, -1);
  EXPECT_NEAR(ball_touch_triangle(V(0.5, 0.5, 10), down, 1, t0, t1, t2), 9, 1e-12);     // the face
  EXPECT_NEAR(ball_touch_triangle(V(1, -0.6, 10), down, 1, t0, t1, t2), 9.2, 1e-12);    // edge t0-t1: 10 - 0.8
  EXPECT_NEAR(ball_touch_triangle(V(-0.6, -0.8, 10), down, 1, t0, t1, t2), 10, 1e-12);  // corner t0, 1 away in xy
  EXPECT_TRUE(std::isinf(ball_touch_triangle(V(-0.8, -0.8, 10), down, 1, t0, t1, t2)));  // passes by
  EXPECT_NEAR(ball_touch_triangle(V(0.5, 0.5, -10), V(0, 0, 1), 1, t0, t1, t2), 9, 1e-12);  // from below
  EXPECT_NEAR(ball_touch_triangle(V(-5, 0.5, 0.5), V(1, 0, 0), 1, t0, t1, t2), 5 - std::sqrt(0.75), 1e-12);  // edge-on
}

// Against marching on random triangles, starts and directions: where it says the ball touches,
// the triangle is r away (to 1e-9), and nowhere before that is it nearer than r.
TEST(BallTouchTriangle, TheBallTouchesThereAndNotBefore) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2, 2);
  int touched = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const V a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const double r = 0.2 + 0.3 * (u(rng) + 2);
    V o(4 * u(rng), 4 * u(rng), 4 * u(rng));
    if ((closest_on_triangle(o, a, b, c) - o).norm() <= r) continue;
    // aimed at a random point of the triangle's box, or anywhere
    V d = trial % 2 ? V(a + (b - a) * 0.3 + (c - a) * 0.3 + 0.5 * V(u(rng), u(rng), u(rng)) - o) : V(u(rng), u(rng), u(rng));
    d.normalize();
    const double t = ball_touch_triangle(o, d, r, a, b, c);
    auto distance = [&](double s) { return (closest_on_triangle(o + s * d, a, b, c) - (o + s * d)).norm(); };
    const double end = std::isfinite(t) ? t : 20.0;
    if (std::isfinite(t)) {
      ++touched;
      EXPECT_NEAR(distance(t), r, 1e-9) << trial;
    }
    for (int k = 0; k < 2000; ++k) EXPECT_GT(distance(end * k / 2000.0), r - 1e-12) << trial << " " << k;
  }
  EXPECT_GT(touched, 100);
}

}  // namespace
}  // namespace scallop
