#include "nodes/geom/crease_surface.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// Points on z = f(x, y) in the disc of radius 0.8 about (cx, 0), on a jittered grid 0.15 apart
// (a random cloud's spacing beside a face 0.3-0.5 mm long).
template <class F>
std::vector<V> points_on(F f, double cx, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  std::vector<V> pts;
  for (double x = -0.8; x <= 0.8; x += 0.15)
    for (double y = -0.8; y <= 0.8; y += 0.15) {
      const double px = cx + x + jitter(rng), py = y + jitter(rng);
      if (x * x + y * y <= 0.64) pts.push_back(V(px, py, f(px, py)));
    }
  return pts;
}

TEST(CreaseSurface, ARidgeOfTwoPlanesIsFoundExactly) {
  // z = 0.1 - 0.12 |x - 0.13|: a 13.7-degree crest along y at x = 0.13.
  const double slope = 0.12, at = 0.13;
  const auto roof = [&](double x, double) { return 0.1 - slope * std::abs(x - at); };
  const auto pts = points_on(roof, 0, 1);
  const auto s = fit_crease_surface(pts, V(0, 0, 1), {V(-0.15, 0.02, 1).normalized(), V(0.1, -0.03, 1).normalized()});
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->ridge);
  EXPECT_LT(s->misfit, 1e-12);
  for (double x = -0.7; x <= 0.7; x += 0.01) {
    const V p(x, 0.2, -0.05);
    EXPECT_NEAR(s->height(p), roof(x, 0.2) - p.z(), 1e-12) << x;
  }
}

TEST(CreaseSurface, AValleyIsTheHigherOfItsPlanes) {
  const auto trough = [](double x, double y) { return 0.05 * y + 0.08 * std::abs(x + 0.2); };
  const auto pts = points_on(trough, 0, 2);
  const auto s = fit_crease_surface(pts, V(0, 0, 1), {V(0.05, 0, 1), V(-0.05, 0, 1)});
  ASSERT_TRUE(s);
  EXPECT_FALSE(s->ridge);
  EXPECT_LT(s->misfit, 1e-12);
  EXPECT_NEAR(s->height(V(-0.2, 0.3, 0)), trough(-0.2, 0.3), 1e-12);  // on the crease line
  EXPECT_NEAR(s->height(V(0.5, -0.4, 0.01)), trough(0.5, -0.4) - 0.01, 1e-12);
}

// The most a ridge stands above a triangle and a valley below it: at the place the crease's line
// crosses an edge, between any grid's points. Triangle (0,0,0) (1.9,0,0) (0,1.3,0) under the
// ridge z = 0.02 - 0.139 |x - 0.77|: above it by 0.02 at x = 0.77 on the edges y = 0 and the
// hypotenuse, below it by 0.139 * 1.13 - 0.02 at the corner (1.9, 0). A grid of sixths (nearest
// x = 0.633) finds it 0.001 above.
TEST(CreaseSurface, ItsExtremesOverATriangleAreWhereItsLineCrossesTheEdges) {
  const double slope = 0.139, at = 0.77;
  for (const double sign : {1.0, -1.0}) {  // the ridge, then the same valley (the most below at its line)
    const auto crease = [&](double x, double) { return sign * (0.02 - slope * std::abs(x - at)); };
    const auto s = fit_crease_surface(points_on(crease, 0.8, 4), V(0, 0, 1), {V(-0.14, 0, 1), V(0.14, 0, 1)});
    ASSERT_TRUE(s);
    EXPECT_EQ(s->ridge, sign > 0);
    const auto [above, below] = s->extremes_over(V(0, 0, 0), V(1.9, 0, 0), V(0, 1.3, 0));
    EXPECT_NEAR(sign > 0 ? above : below, 0.02, 1e-12);
    EXPECT_NEAR(sign > 0 ? below : above, slope * (1.9 - at) - 0.02, 1e-12);
  }
}

TEST(CreaseSurface, PointsOnOnePlaneGiveThatPlane) {
  const auto plane = [](double x, double y) { return 0.3 * x - 0.1 * y + 2; };
  const auto pts = points_on(plane, 1, 3);
  const auto s = fit_crease_surface(pts, V(0, 0, 1), {V(0.1, 0, 1), V(-0.1, 0, 1)});
  ASSERT_TRUE(s);
  EXPECT_LT(s->misfit, 1e-12);
  EXPECT_NEAR(s->height(V(1.2, 0.5, 0)), plane(1.2, 0.5), 1e-12);
}

TEST(CreaseSurface, ACurvedSurfaceIsMissedNotPretended) {
  // A sphere of radius 2: two planes meeting in a line cannot follow it along their line (the
  // points' heights fall 0.16 mm from the middle to the rim that way), and the misfit says so.
  const double R = 2;
  const auto sphere = [&](double x, double y) { return std::sqrt(R * R - x * x - y * y); };
  const auto pts = points_on(sphere, 0, 4);
  const auto s = fit_crease_surface(pts, V(0, 0, 1), {V(0.2, 0, 1), V(-0.2, 0, 1)});
  ASSERT_TRUE(s);
  double worst = 0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(s->height(p)));
  EXPECT_DOUBLE_EQ(s->misfit, worst);
  EXPECT_GT(s->misfit, 0.01);
}

TEST(CreaseSurface, APlaneSteeperThanSixtyDegreesToUpIsRefused) {
  const auto wall = [](double x, double) { return 2 * x; };  // 63 degrees
  const auto pts = points_on(wall, 0, 5);
  EXPECT_FALSE(fit_crease_surface(pts, V(0, 0, 1), {V(-2, 0, 1), V(-2, 0.1, 1)}));
  EXPECT_FALSE(fit_crease_surface({V(0, 0, 0), V(1, 0, 0)}, V(0, 0, 1), {V(0, 0, 1), V(0, 0, 1)}));
}

}  // namespace
}  // namespace scallop
