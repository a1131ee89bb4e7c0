#include "nodes/path/uv_interpolation.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

using namespace scallop;

namespace {
// A jittered grid over [0,10] x [0,8] (uv = xy) lifted by z = f(x, y) with exact normals.
struct Patch {
  std::vector<Eigen::Vector3d> P, N;
  std::vector<Eigen::Vector2d> UV;
};
template <class F, class G>
Patch make_patch(F z, G grad) {
  Patch p;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jit(-0.1, 0.1);
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 32; ++j) {
      const double x = std::clamp(i * 0.25 + jit(rng), 0.0, 10.0);
      const double y = std::clamp(j * 0.25 + jit(rng), 0.0, 8.0);
      const Eigen::Vector2d g = grad(x, y);
      p.P.emplace_back(x, y, z(x, y));
      p.N.push_back(Eigen::Vector3d(-g.x(), -g.y(), 1).normalized());
      p.UV.emplace_back(x, y);
    }
  return p;
}
UVDomain rect() {
  UVDomain d;
  d.kind = UVDomain::Kind::Rectangle;
  d.width = 10;
  d.height = 8;
  return d;
}
}  // namespace

TEST(UVInterpolation, ReproducesAPlaneExactly) {
  auto z = [](double x, double y) { return 1 + 0.2 * x - 0.3 * y; };
  auto g = [](double, double) { return Eigen::Vector2d(0.2, -0.3); };
  const Patch p = make_patch(z, g);
  const UVInterpolator f(p.P, p.N, p.UV, rect());
  const Eigen::Vector3d n = Eigen::Vector3d(-0.2, 0.3, 1).normalized();
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(3.3, 4.1), Eigen::Vector2d(0, 0),
                                  Eigen::Vector2d(9.99, 7.5), Eigen::Vector2d(5, 8)}) {
    const SurfaceSample s = f(q);
    EXPECT_NEAR((s.position - Eigen::Vector3d(q.x(), q.y(), z(q.x(), q.y()))).norm(), 0, 1e-10);
    EXPECT_NEAR((s.normal - n).norm(), 0, 1e-10);
  }
}

TEST(UVInterpolation, ReproducesAQuadricInside) {
  auto z = [](double x, double y) { return 0.05 * x * x - 0.02 * x * y + 0.03 * y * y; };
  auto g = [](double x, double y) { return Eigen::Vector2d(0.1 * x - 0.02 * y, -0.02 * x + 0.06 * y); };
  const Patch p = make_patch(z, g);
  const UVInterpolator f(p.P, p.N, p.UV, rect());
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(3.3, 4.1), Eigen::Vector2d(6.07, 2.2)}) {
    const SurfaceSample s = f(q);
    EXPECT_NEAR((s.position - Eigen::Vector3d(q.x(), q.y(), z(q.x(), q.y()))).norm(), 0, 1e-10);
  }
}

TEST(UVInterpolation, NormalIsThatOfTheFittedSurfaceNotOfBiasedPointNormals) {
  // Point normals tilted by 0.01 rad (as PCA normals lean on a curved surface): the returned
  // normal comes from the fitted quadric, exact inside; the ball centre r n would otherwise
  // move r x 0.01 sideways.
  auto z = [](double x, double y) { return 0.05 * x * x - 0.02 * x * y + 0.03 * y * y; };
  auto g = [](double x, double y) { return Eigen::Vector2d(0.1 * x - 0.02 * y, -0.02 * x + 0.06 * y); };
  Patch p = make_patch(z, g);
  const Eigen::AngleAxisd tilt(0.01, Eigen::Vector3d::UnitX());
  for (auto& n : p.N) n = tilt * n;
  const UVInterpolator f(p.P, p.N, p.UV, rect());
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(3.3, 4.1), Eigen::Vector2d(6.07, 2.2)}) {
    const Eigen::Vector2d gr = g(q.x(), q.y());
    const Eigen::Vector3d exact = Eigen::Vector3d(-gr.x(), -gr.y(), 1).normalized();
    EXPECT_NEAR((f(q).normal - exact).norm(), 0, 1e-9);
  }
  // On the edge the fit extrapolates: there the point normals are used.
  const Eigen::Vector2d e(5, 0);
  const Eigen::Vector2d gr = g(e.x(), e.y());
  const Eigen::Vector3d biased = tilt * Eigen::Vector3d(-gr.x(), -gr.y(), 1).normalized();
  EXPECT_NEAR((f(e).normal - biased).norm(), 0, 2e-3);
}

TEST(UVInterpolation, ClampsOutsideTheDomain) {
  auto z = [](double x, double y) { return std::sin(x) + y * y * 0.1; };
  auto g = [](double x, double y) { return Eigen::Vector2d(std::cos(x), 0.2 * y); };
  const Patch p = make_patch(z, g);
  const UVInterpolator f(p.P, p.N, p.UV, rect());
  EXPECT_EQ(f({-3, 2}).position, f({0, 2}).position);
  EXPECT_EQ(f({12, 9}).position, f({10, 8}).position);
  UVDomain disk;
  disk.kind = UVDomain::Kind::Disk;
  disk.radius = 2;
  EXPECT_NEAR((disk.clamp({3, 4}) - Eigen::Vector2d(1.2, 1.6)).norm(), 0, 1e-15);
  EXPECT_EQ(disk.clamp({0.5, 0.5}), Eigen::Vector2d(0.5, 0.5));
}

TEST(UVInterpolation, SpacingOfARegularGrid) {
  std::vector<Eigen::Vector3d> P, N;
  std::vector<Eigen::Vector2d> UV;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) {
      P.emplace_back(i * 0.5, j * 0.5, 0);
      N.emplace_back(0, 0, 1);
      UV.emplace_back(i * 0.5, j * 0.5);
    }
  UVDomain d;
  d.width = d.height = 9.5;
  const UVInterpolator f(P, N, UV, d);
  EXPECT_DOUBLE_EQ(f.uv_spacing(), 0.5);
}

TEST(UVInterpolation, BadInput) {
  std::vector<Eigen::Vector3d> P(30, Eigen::Vector3d::Zero()), N(29, Eigen::Vector3d::UnitZ());
  std::vector<Eigen::Vector2d> UV(30, Eigen::Vector2d::Zero());
  try {
    UVInterpolator f(P, N, UV, rect());
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "positions, normals and uv differ in count (30, 29, 30)");
  }
  N.push_back(Eigen::Vector3d::UnitZ());
  try {
    UVInterpolator f(P, N, UV, rect(), 4);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the interpolation needs 6 to 64 neighbours per fit (got 4)");
  }
}

TEST(UVInterpolation, CarriesThePointsUncertainty) {
  auto z = [](double x, double y) { return 0.1 * x * y; };
  auto g = [](double x, double y) { return Eigen::Vector2d(0.1 * y, 0.1 * x); };
  const Patch p = make_patch(z, g);
  // uniform: the same bound everywhere, at the edge too
  const std::vector<double> U(p.P.size(), 0.004);
  const UVInterpolator f(p.P, p.N, p.UV, rect(), 20, &U);
  for (const Eigen::Vector2d& q : {Eigen::Vector2d(3.3, 4.1), Eigen::Vector2d(0, 0)})
    EXPECT_NEAR(f(q).uncertainty, 0.004, 1e-15);
  // a soft maximum: continuous, and where half the fit has 0.003 near 0.003 * 0.5^(1/8)
  std::vector<double> V(p.P.size());
  for (std::size_t i = 0; i < V.size(); ++i) V[i] = p.P[i].x() < 5 ? 0.001 : 0.003;
  const UVInterpolator h(p.P, p.N, p.UV, rect(), 20, &V);
  EXPECT_NEAR(h(Eigen::Vector2d(1, 4)).uncertainty, 0.001, 1e-15);
  EXPECT_NEAR(h(Eigen::Vector2d(9, 4)).uncertainty, 0.003, 1e-15);
  const double mid = h(Eigen::Vector2d(5, 4)).uncertainty;
  EXPECT_GT(mid, 0.0026);
  EXPECT_LT(mid, 0.003);
  EXPECT_NEAR(h(Eigen::Vector2d(5.0001, 4)).uncertainty, mid, 1e-6);
  // without: zero
  EXPECT_EQ(UVInterpolator(p.P, p.N, p.UV, rect())(Eigen::Vector2d(2, 2)).uncertainty, 0.0);
  const std::vector<double> short_u(3, 0.0);
  try {
    UVInterpolator bad(p.P, p.N, p.UV, rect(), 20, &short_u);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "the cloud has 1353 points but 3 uncertainties");
  }
}
