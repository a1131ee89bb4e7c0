#include "nodes/path/step_size.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace scallop;

TEST(StepSize, SideIntervalOnAPlaneIsSqrt8rh) {
  EXPECT_DOUBLE_EQ(side_interval(0.01, 3.0, 0.0), std::sqrt(8 * 3.0 * 0.01));
  EXPECT_DOUBLE_EQ(side_interval(0.05, 4.0, 0.0), std::sqrt(8 * 4.0 * 0.05));
}

TEST(StepSize, SideIntervalConvexAndConcave) {
  const double h = 0.02, r = 5, R = 40;
  // Convex: sqrt(8 h r R / (R + r)); concave: sqrt(8 h r R / (R - r)).
  EXPECT_NEAR(side_interval(h, r, 1 / R), std::sqrt(8 * h * r * R / (R + r)), 1e-14);
  EXPECT_NEAR(side_interval(h, r, -1 / R), std::sqrt(8 * h * r * R / (R - r)), 1e-14);
  EXPECT_LT(side_interval(h, r, 1 / R), side_interval(h, r, 0));
  EXPECT_GT(side_interval(h, r, -1 / R), side_interval(h, r, 0));
}

TEST(StepSize, ConcaveTighterThanTheBallIsUnreachable) {
  EXPECT_TRUE(ball_cannot_reach(3.0, -1 / 2.0));
  EXPECT_FALSE(ball_cannot_reach(3.0, -1 / 4.0));
  EXPECT_FALSE(ball_cannot_reach(3.0, 1 / 2.0));
  EXPECT_TRUE(std::isinf(side_interval(0.01, 3.0, -1 / 2.0)));
}

TEST(StepSize, ForwardIntervalFormula2) {
  EXPECT_TRUE(std::isinf(forward_interval(0.01, 0.0)));  // straight pass: no limit
  const double e = 0.005, R = 30;
  EXPECT_DOUBLE_EQ(forward_interval(e, 1 / R), std::sqrt(8 * e * R - 4 * e * e));
  // The sagitta of that chord on a circle of radius R is exactly e.
  const double l = forward_interval(e, 1 / R);
  EXPECT_NEAR(R - std::sqrt(R * R - l * l / 4), e, 1e-12);
  // ~ 2 sqrt(2 R e) for e << R.
  EXPECT_NEAR(l, 2 * std::sqrt(2 * R * e), 1e-4);
  EXPECT_DOUBLE_EQ(forward_interval(10.0, 1 / 2.0), 4.0);  // e beyond the diameter
}

TEST(StepSize, ConformalAndCorrectedSideSteps) {
  EXPECT_DOUBLE_EQ(side_step_conformal(1.2, 2.0), 0.6);
  EXPECT_NEAR(side_step_corrected(1.2, 2.0, M_PI / 2), 0.6, 1e-15);
  // At 60 degrees the iso-lines du apart are du |r_u| sin 60 apart on the surface.
  const double du = side_step_corrected(1.2, 2.0, M_PI / 3);
  EXPECT_NEAR(du * 2.0 * std::sin(M_PI / 3), 1.2, 1e-14);
  EXPECT_NEAR(side_step_corrected(1.2, 2.0, 2 * M_PI / 3), du, 1e-14);
}

TEST(StepSize, CurvaturesOfASphereAndACylinder) {
  // Sphere of radius R seen from outside (convex), at its top, u = x, v = y.
  const double R = 25;
  const Eigen::Vector3d ru(1, 0, 0), rv(0, 1, 0), n(0, 0, 1);
  const Eigen::Vector3d ruu(0, 0, -1 / R), rvv(0, 0, -1 / R), ruv(0, 0, 0);
  const FundamentalForms f = fundamental_forms(ru, rv, ruu, ruv, rvv, n);
  EXPECT_NEAR(normal_curvature(f, 1, 0), 1 / R, 1e-15);
  EXPECT_NEAR(normal_curvature(f, 1, 1), 1 / R, 1e-15);
  const Eigen::Vector2d k = principal_curvatures(f);
  EXPECT_NEAR(k[0], 1 / R, 1e-15);
  EXPECT_NEAR(k[1], 1 / R, 1e-15);
  // A trough (concave cylinder along u): curvatures {-1/R, 0}.
  const FundamentalForms g = fundamental_forms(ru, rv, Eigen::Vector3d::Zero(), ruv,
                                               Eigen::Vector3d(0, 0, 1 / R), n);
  const Eigen::Vector2d kg = principal_curvatures(g);
  EXPECT_NEAR(kg[0], -1 / R, 1e-15);
  EXPECT_NEAR(kg[1], 0, 1e-15);
  EXPECT_NEAR(normal_curvature(g, 0, 3), -1 / R, 1e-15);
}

TEST(StepSize, CuspHeightOnAPlane) {
  const double r = 4, h = 0.05;
  // sqrt(8 r h) is the first-order spacing; the exact cusp there is a little higher.
  const double w = std::sqrt(8 * r * h);
  EXPECT_NEAR(cusp_height_plane(r, w), r - std::sqrt(r * r - 2 * r * h), 1e-15);
  EXPECT_GT(cusp_height_plane(r, w), h);
  EXPECT_NEAR(cusp_height_plane(r, 2 * std::sqrt(2 * r * h - h * h)), h, 1e-14);
}

TEST(StepSize, RayCapsuleEntry) {
  const Eigen::Vector3d up(0, 0, 1);
  const Eigen::Vector3d a(-1, 0, 5), b(1, 0, 5);
  EXPECT_NEAR(ray_capsule_entry({0, 0, 0}, up, a, b, 2), 3, 1e-14);           // body
  EXPECT_NEAR(ray_capsule_entry({2, 0, 0}, up, a, b, 2), 5 - std::sqrt(3.0), 1e-14);  // cap
  EXPECT_EQ(ray_capsule_entry({0, 0, 4}, up, a, b, 2), 0);                    // inside
  EXPECT_TRUE(std::isinf(ray_capsule_entry({5, 0, 0}, up, a, b, 2)));         // misses
  EXPECT_TRUE(std::isinf(ray_capsule_entry({0, 0, 10}, up, a, b, 2)));        // behind
  EXPECT_NEAR(ray_capsule_entry({0.5, 0, 0}, up, a, a, 2), 5 - std::sqrt(4 - 2.25), 1e-14);  // ball
  // Given `before`: the segment 5 from o cannot be entered before 5 - 2 = 3
  EXPECT_TRUE(std::isinf(ray_capsule_entry({0, 0, 0}, up, a, b, 2, 2.99)));
  EXPECT_NEAR(ray_capsule_entry({0, 0, 0}, up, a, b, 2, 3.01), 3, 1e-14);
  EXPECT_EQ(ray_capsule_entry({0, 0, 4}, up, a, b, 2, 0.5), 0);  // inside whatever the bound
}
