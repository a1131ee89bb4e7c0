// B-spline bases and surfaces against closed forms: knots, partition of unity, a Bezier patch.
#include "nodes/geom/bspline_surface.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tbb/parallel_for.h>
#include <vector>

#include "nodes/path/step_size.h"

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


// r(u, v) = (10 u, 20 v, 5 u^2) exactly: degree 2 in u (Bezier poles of u^2: 0, 0, 1), 1 in v.
BSplineSurface parabolic_cylinder() {
  BSplineSurface s;
  s.degree_u = 2, s.degree_v = 1;
  s.knots_u = {0, 0, 0, 1, 1, 1};
  s.knots_v = {0, 0, 1, 1};
  s.poles_u = 3, s.poles_v = 2;
  for (double y : {0.0, 20.0})
    for (int i = 0; i < 3; ++i) s.poles.push_back({5.0 * i, y, i == 2 ? 5.0 : 0.0});
  return s;
}

TEST(BSplinePatch, DerivativesNormalAndCurvatureOfAParabolicCylinder) {
  const BSplinePatch up(parabolic_cylinder(), {0, 0, 1});
  for (double u : {0.0, 0.3, 1.0})
    for (double v : {0.0, 0.5}) {
      const SurfaceDerivatives d = up.derivatives({u, v});
      EXPECT_LT((d.sample.position - Eigen::Vector3d(10 * u, 20 * v, 5 * u * u)).norm(), 1e-12);
      EXPECT_LT((d.ru - Eigen::Vector3d(10, 0, 10 * u)).norm(), 1e-12);
      EXPECT_LT((d.rv - Eigen::Vector3d(0, 20, 0)).norm(), 1e-12);
      EXPECT_LT((d.ruu - Eigen::Vector3d(0, 0, 10)).norm(), 1e-12);
      EXPECT_LT(d.ruv.norm() + d.rvv.norm(), 1e-12);
      // n = (-z_x, 0, 1) / |.| with z = x^2 / 20: z_x = x / 10 = u.
      EXPECT_LT((d.sample.normal - Eigen::Vector3d(-u, 0, 1).normalized()).norm(), 1e-12);
      // A bowl seen from the tool: kappa = -z'' / (1 + z'^2)^(3/2) with z'' = 1/10.
      const Eigen::Vector2d k = principal_curvatures(fundamental_forms(d.ru, d.rv, d.ruu, d.ruv, d.rvv, d.sample.normal));
      EXPECT_NEAR(k[0], -0.1 / std::pow(1 + u * u, 1.5), 1e-12);
      EXPECT_NEAR(k[1], 0.0, 1e-12);
    }
  // Seen from below, the normal turns over and the bowl is a dome.
  const BSplinePatch down(parabolic_cylinder(), {0, 0, -1});
  EXPECT_LT((down({0, 0.5}).normal - Eigen::Vector3d(0, 0, -1)).norm(), 1e-12);
}

TEST(BSplinePatch, TheDefaultFiniteDifferencesAgreeWithTheExactDerivatives) {
  // The base class's central differences, through operator() only.
  struct PointsOnly final : ParametricSurface {
    const BSplinePatch& p;
    explicit PointsOnly(const BSplinePatch& patch) : p(patch) {}
    SurfaceSample operator()(const Eigen::Vector2d& uv) const override { return p(uv); }
    const UVDomain& domain() const override { return p.domain(); }
    double uv_spacing() const override { return 1e-3; }
  };
  const BSplinePatch patch(parabolic_cylinder(), {0, 0, 1});
  const PointsOnly numeric(patch);
  for (double u : {0.0, 0.4, 1.0}) {
    // On the domain's edges the stencil's centre moves inside by its step, 2 uv_spacing.
    const double centre = std::clamp(u, 2e-3, 1 - 2e-3);
    const SurfaceDerivatives a = patch.derivatives({centre, 0.5}), b = numeric.derivatives({u, 0.5});
    EXPECT_LT((a.ru - b.ru).norm(), 1e-6);
    EXPECT_LT((a.rv - b.rv).norm(), 1e-6);
    EXPECT_LT((a.ruu - b.ruu).norm(), 1e-4);
    EXPECT_LT((a.ruv - b.ruv).norm() + (a.rvv - b.rvv).norm(), 1e-4);
    EXPECT_EQ(patch({u, 0.5}).position, b.sample.position);
  }
  EXPECT_EQ(patch.domain().width, 1.0);
  EXPECT_DOUBLE_EQ(patch.uv_spacing(), 0.25);
}

TEST(BSplinePatch, WhereTheMapIsDegenerateTheNormalComesFromInsideTheCap) {
  // A bilinear patch whose corner (1, 0) is nearly 180 degrees: ru = (10, 0, 0) and rv = (10, 0.1,
  // 0.2) there, so ru x rv = (0, -2, 1) stands 63 degrees off a surface that is nearly z = 0.
  BSplineSurface s;
  s.degree_u = s.degree_v = 1;
  s.knots_u = s.knots_v = {0, 0, 1, 1};
  s.poles_u = s.poles_v = 2;
  s.poles = {{0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {20, 0.1, 0.2}};
  const Eigen::Vector3d z(0, 0, 1);
  const BSplinePatch plain(s, z), capped(s, z, 0, 0.95);
  EXPECT_NEAR(plain({1, 0}).normal.dot(z), 1 / std::sqrt(5.0), 1e-12);
  const SurfaceDerivatives a = plain.derivatives({1, 0}), b = capped.derivatives({1, 0});
  EXPECT_GE(b.sample.normal.dot(z), 0.95);
  EXPECT_NEAR(b.sample.normal.norm(), 1, 1e-12);
  EXPECT_EQ(a.sample.position, b.sample.position);  // only the normal is taken from inside
  EXPECT_EQ(a.ru, b.ru);
  EXPECT_EQ(a.rv, b.rv);
  // Inside, where ru x rv lies within the cap, both agree.
  EXPECT_EQ(plain({0.5, 0.5}).normal, capped({0.5, 0.5}).normal);
  EXPECT_GT(capped({0.5, 0.5}).normal.dot(z), 0.999);
}

TEST(BSplinePatch, EachPatchAnswersForItselfWhateverWasAskedBeforeOnAnyThread) {
  // Each thread keeps the last basis it evaluated for a patch: two patches with the same knots but
  // other poles, asked in turn at the same (u, v), and from many threads at once, answer as the
  // surface alone does (evaluate, which keeps nothing), to the last bit.
  BSplineSurface raised = parabolic_cylinder();
  for (auto& p : raised.poles) p.z() += 3 + p.x() / 7;
  const BSplinePatch a(parabolic_cylinder(), {0, 0, 1}), b(raised, {0, 0, 1});
  const BSplinePatch a_copy = a;  // the same surface: the same answers
  const auto exact = [](const BSplinePatch& p, double u, double v) { return evaluate(p.surface(), u, v, 1).point; };
  for (double u : {0.0, 0.25, 0.25, 0.7})
    for (double v : {0.5, 0.5, 0.1})
      for (const BSplinePatch* p : {&a, &b, &a_copy, &a}) {
        EXPECT_EQ((*p)({u, v}).position, exact(*p, u, v));
        EXPECT_EQ(p->derivatives({u, v}).ruu, evaluate(p->surface(), u, v).duu);
      }
  std::vector<Eigen::Vector3d> got(4000);
  tbb::parallel_for(std::size_t(0), got.size(), [&](std::size_t i) {
    const BSplinePatch& p = i % 3 == 0 ? b : a;
    got[i] = p({double(i % 17) / 16, double(i % 5) / 4}).position;
  });
  for (std::size_t i = 0; i < got.size(); ++i)
    ASSERT_EQ(got[i], exact(i % 3 == 0 ? b : a, double(i % 17) / 16, double(i % 5) / 4)) << i;
  EXPECT_THROW(evaluate(a.surface(), 0.5, 0.5, 3), std::invalid_argument);
}

TEST(BSplinePatch, RefusesABadSurface) {
  BSplineSurface s = parabolic_cylinder();
  s.poles.pop_back();
  EXPECT_THROW(BSplinePatch(s, {0, 0, 1}), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
