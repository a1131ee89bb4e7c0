// B-spline bases and surfaces against closed forms: knots, partition of unity, a Bezier patch.
#include "nodes/geom/bspline_surface.h"

#include <gtest/gtest.h>

#include <cmath>

namespace scallop {
namespace {

TEST(BSplineSurface, ClampedUniformKnots) {
  EXPECT_EQ(clamped_uniform_knots(4, 3), (std::vector<double>{0, 0, 0, 0, 1, 1, 1, 1}));
  EXPECT_EQ(clamped_uniform_knots(2, 1), (std::vector<double>{0, 0, 1, 1}));
  const auto k = clamped_uniform_knots(6, 3);
  ASSERT_EQ(k.size(), 10u);
  EXPECT_DOUBLE_EQ(k[4], 1.0 / 3);
  EXPECT_DOUBLE_EQ(k[5], 2.0 / 3);
  EXPECT_THROW(clamped_uniform_knots(3, 3), std::invalid_argument);
}

TEST(BSplineSurface, AveragedKnotsAreTheMeansOfTheParameters) {
  // 7 points at k / 6, degree 3: inner knots (1 + 2 + 3) / 18 = 1/3, (2 + 3 + 4) / 18 = 1/2, 2/3.
  const auto k = averaged_knots(7, 3);
  ASSERT_EQ(k.size(), 11u);
  EXPECT_DOUBLE_EQ(k[4], 1.0 / 3);
  EXPECT_DOUBLE_EQ(k[5], 0.5);
  EXPECT_DOUBLE_EQ(k[6], 2.0 / 3);
  EXPECT_EQ(k[3], 0.0);
  EXPECT_EQ(k[7], 1.0);
  EXPECT_EQ(averaged_knots(4, 3), clamped_uniform_knots(4, 3));
}

TEST(BSplineSurface, BasisIsAPartitionOfUnityAndItsDerivativesSumToZero) {
  const auto k = clamped_uniform_knots(9, 3);
  for (double t = 0; t <= 1.0; t += 0.0625) {
    const BasisAt b = bspline_basis(k, 3, t, 2);
    EXPECT_GE(b.first, 0);
    EXPECT_LE(b.first + 3, 8);
    EXPECT_NEAR(b.values.row(0).sum(), 1.0, 1e-14) << t;
    EXPECT_NEAR(b.values.row(1).sum(), 0.0, 1e-11) << t;
    EXPECT_NEAR(b.values.row(2).sum(), 0.0, 1e-9) << t;
    EXPECT_GE(b.values.row(0).minCoeff(), -1e-15);
  }
}

// Poles (i/3, j/3, (i/3)(j/3)) of a bicubic Bezier patch: by the Bernstein polynomials' linear
// precision, S(u, v) = (u, v, u v).
TEST(BSplineSurface, ABezierPatchWithLinearPolesIsTheSaddleUV) {
  BSplineSurface s;
  s.knots_u = s.knots_v = clamped_uniform_knots(4, 3);
  s.poles_u = s.poles_v = 4;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) s.poles.push_back({i / 3.0, j / 3.0, i / 3.0 * j / 3.0});
  EXPECT_EQ(bspline_problem(s), "");
  for (double u : {0.0, 0.3, 0.77, 1.0})
    for (double v : {0.0, 0.5, 0.91, 1.0}) {
      const SurfaceJet j = evaluate(s, u, v);
      EXPECT_LT((j.point - Eigen::Vector3d(u, v, u * v)).norm(), 1e-14);
      EXPECT_LT((surface_point(s, u, v) - j.point).norm(), 1e-15);
      EXPECT_LT((j.du - Eigen::Vector3d(1, 0, v)).norm(), 1e-13);
      EXPECT_LT((j.dv - Eigen::Vector3d(0, 1, u)).norm(), 1e-13);
      EXPECT_LT(j.duu.norm(), 1e-12);
      EXPECT_LT(j.dvv.norm(), 1e-12);
      EXPECT_LT((j.duv - Eigen::Vector3d(0, 0, 1)).norm(), 1e-12);
    }
}

TEST(BSplineSurface, ProblemsAreNamed) {
  BSplineSurface s;
  s.knots_u = s.knots_v = clamped_uniform_knots(4, 3);
  s.poles_u = s.poles_v = 4;
  s.poles.assign(15, Eigen::Vector3d::Zero());
  EXPECT_EQ(bspline_problem(s), "15 poles for a 4 by 4 net");
  s.poles.push_back(Eigen::Vector3d(NAN, 0, 0));
  EXPECT_EQ(bspline_problem(s), "a pole is not finite");
  s.knots_v = {0, 0, 0, 0, 0.5, 1, 1, 1, 1};
  EXPECT_EQ(bspline_problem(s), "9 knots in v for 4 poles of degree 3");
  s.knots_v = {0, 0, 0, 0.5, 1, 1, 1, 1};
  EXPECT_EQ(bspline_problem(s), "knots in v not clamped to [0, 1]");
  s.knots_u = {0, 0, 0, 0, 1, 1, 0.5, 1};
  EXPECT_EQ(bspline_problem(s), "knots in u not increasing at 6");
}

}  // namespace
}  // namespace scallop
