#include "nodes/post/simulate.h"
#include "nodes/geom/obstacle_points.h"
#include "nodes/post/clearance_march.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// Tilted plane z = 5 + 0.2 x + 0.25 y (n_z = 1/1.05 exactly) over [0, 16] × [0, 12].
constexpr double kA = 0.2, kB = 0.25, kC = 5.0;
double plane_z(double x, double y) { return kC + kA * x + kB * y; }
const Eigen::Vector3d kNormal = Eigen::Vector3d(-kA, -kB, 1).normalized();

std::vector<Eigen::Vector3d> plane_cloud() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> jitter(-0.08, 0.08);
  std::vector<Eigen::Vector3d> P;
  for (double x = 0; x <= 16 + 1e-9; x += 0.25)
    for (double y = 0; y <= 12 + 1e-9; y += 0.25) {
      double xx = std::clamp(x + jitter(rng), 0.0, 16.0), yy = std::clamp(y + jitter(rng), 0.0, 12.0);
      P.emplace_back(xx, yy, plane_z(xx, yy));
    }
  return P;
}

// Raster of passes along x at contact y = y0 + j s (j < passes), extended 1 mm past the patch.
Toolpath raster(double r, double s, double dz = 0, int skip = -1) {
  Toolpath t;
  t.tool_radius = r;
  t.scallop_height = 0.02;
  t.pattern = "zigzag";
  int j = 0;
  for (double y = -1; y <= 13 + 1e-9; y += s, ++j) {
    if (j == skip) continue;
    ToolpathPass p;
    for (double x = -1; x <= 17 + 1e-9; x += 0.5) {
      p.contact.emplace_back(x, y, plane_z(x, y) + dz);
      p.normal.push_back(kNormal);
    }
    t.passes.push_back(p);
  }
  return t;
}

// Distance between neighbouring centre lines, measured perpendicular to them.
double line_gap(double s) {
  Eigen::Vector3d step(0, s, kB * s), dir = Eigen::Vector3d(1, 0, kA).normalized();
  return (step - step.dot(dir) * dir).norm();
}

// The options the plane's tests simulate with: a grid of 0.08 mm.
SimulateOptions plane_options(double r, double h, double chord = 0) {
  SimulateOptions o;
  o.tool_radius = r;
  o.scallop = h;
  o.chord = chord;
  o.spacing = 0.08;
  return o;
}

Simulation run(const Toolpath& t, double h) {
  static const auto cloud = plane_cloud();
  HeightFieldModel surf(cloud);
  return simulate_cut(surf, feed_centres(t), 0.0, plane_options(t.tool_radius, h));
}

TEST(Simulate, HeightFieldReproducesAPlane) {
  HeightFieldModel surf(plane_cloud());
  double z;
  Eigen::Vector3d n;
  ASSERT_TRUE(surf.eval(7.3, 4.1, z, n));
  EXPECT_NEAR(z, plane_z(7.3, 4.1), 1e-9);
  EXPECT_NEAR((n - kNormal).norm(), 0, 1e-9);
  EXPECT_FALSE(surf.eval(20, 4, z, n));    // off the patch
  EXPECT_FALSE(surf.eval(16.6, 4, z, n));  // just past the edge
  EXPECT_NEAR(surf.spacing(), 0.25, 0.06);
}

// Sparse cap of a sphere (radius 50, 2.5 mm between points, rings of constant latitude with
// points on common meridians, as a UV-sphere mesh has them) down to 84 degrees of slope. Near the
// rim the rings project onto nearly the same xy lines, and a quadratic z(x, y) through them is
// ill-posed (it put the surface 4 mm too high there and the simulation reported 1.9 mm
// gouges); the model must follow the sphere.
TEST(Simulate, HeightFieldFollowsASteepSparseSphere) {
  const double R = 50;
  std::vector<Eigen::Vector3d> P{{0, 0, R}};
  const double tmax = std::acos(0.098), dth = 2.5 / R;
  for (int i = 1; i * dth <= tmax + 1e-9; ++i) {
    const double th = i * dth;
    const int n = 8 * static_cast<int>(std::ceil(2 * M_PI * R * std::sin(th) / 2.5 / 8));
    for (int j = 0; j < n; ++j) {
      const double ph = 2 * M_PI * j / n;
      P.emplace_back(R * std::sin(th) * std::cos(ph), R * std::sin(th) * std::sin(ph), R * std::cos(th));
    }
  }
  HeightFieldModel surf(P);
  double worst = 0, worst_angle = 0;
  int n = 0;
  const double rho_max = R * std::sin(std::floor(tmax / dth) * dth) - 0.1;
  for (double x = -R; x <= R; x += 0.53)
    for (double y = -R; y <= R; y += 0.61) {
      if (std::hypot(x, y) > rho_max) continue;
      double z;
      Eigen::Vector3d nrm;
      ASSERT_TRUE(surf.eval(x, y, z, nrm, true)) << x << " " << y;
      const Eigen::Vector3d q(x, y, z);
      worst = std::max(worst, std::abs(q.norm() - R));
      worst_angle = std::max(worst_angle, std::acos(std::min(1.0, nrm.dot(q.normalized()))));
      ++n;
    }
  EXPECT_GT(n, 20000);
  EXPECT_LT(worst, 0.005);                 // mm, radially
  EXPECT_LT(worst_angle, 0.3 * M_PI / 180);
}

TEST(Simulate, RasterOnAPlaneLeavesTheClosedFormScallop) {
  const double r = 3, s = 0.7;
  auto res = run(raster(r, s), 0.02);
  const auto& j = res.report;
  double w = line_gap(s);
  double expect = r - std::sqrt(r * r - w * w / 4);
  EXPECT_NEAR(j["scallop_max_interior"].get<double>(), expect, 0.01 * expect);
  EXPECT_LT(j["gouge_max"].get<double>(), 1e-9);
  EXPECT_EQ(j["uncut_fraction"].get<double>(), 0.0);
  EXPECT_NEAR(j["surface_area"].get<double>(), 16 * 12 * 1.05, 0.03 * 16 * 12 * 1.05);
  EXPECT_GT(j["samples"].get<int>(), 25000);
  EXPECT_EQ(j["pass"].get<bool>(), expect <= 1.01 * 0.02);
  EXPECT_EQ(j["worst"].size(), 10u);
  EXPECT_EQ(j["worst"][0]["kind"], "scallop");
}

// The refinement is not crowded out: passes 0.7 apart below y = 6 and 0.62 above leave cusps of
// two heights (0.78 of each other). The lower half's cusps fill the 1000 highest grid values, and
// the grid alone catches the upper cusps up to 0.04 mm off their line (0.0047 mm low); each
// cell's own highest seeds the refinement too, so the upper half's maximum is found as well.
TEST(Simulate, ALowerMaximumElsewhereIsRefinedToo) {
  const double r = 3, s_low = 0.7, s_high = 0.62;
  Toolpath t = raster(r, s_low);
  t.passes.clear();
  for (double y = -1; y <= 13 + 1e-9; y += (y < 6 ? s_low : s_high)) {
    ToolpathPass p;
    for (double x = -1; x <= 17 + 1e-9; x += 0.5) {
      p.contact.emplace_back(x, y, plane_z(x, y));
      p.normal.push_back(kNormal);
    }
    t.passes.push_back(p);
  }
  const auto res = run(t, 0.02);
  const auto cusp = [&](double s) {
    const double w = line_gap(s);
    return r - std::sqrt(r * r - w * w / 4);
  };
  ASSERT_GT(cusp(s_high), 0.75 * cusp(s_low));
  double high = 0;
  std::size_t refined_high = 0;
  for (const auto& q : res.samples)
    if (q.y > 7 && q.y < 11) {
      high = std::max(high, q.scallop);
      refined_high += q.weight == 0;
    }
  EXPECT_GT(refined_high, 0u);
  EXPECT_NEAR(high, cusp(s_high), 0.01 * cusp(s_high));
  EXPECT_NEAR(res.report["scallop_max_interior"].get<double>(), cusp(s_low), 0.01 * cusp(s_low));
}

// A wall the trim left out beside the plane (points on x = 16.5, from 1 mm below the plane to
// 8 above it): where the ball touching the plane (its centre r n away, n_x = -0.2 / 1.05) would
// come within r + half the cloud's spacing of it, from x0 = 16.5 + 3 * 0.2 / 1.05 - 3 - sp / 2 on,
// no ball reaches. That band is reported (its area and where), not counted as uncut or scallop.
TEST(Simulate, BesideWhatWasLeftOutNoBallReachesAndItIsReportedNotCounted) {
  const double r = 3, s = 0.7;
  static const auto cloud = plane_cloud();
  HeightFieldModel surf(cloud);
  std::vector<Eigen::Vector3d> wall;
  for (double y = -1; y <= 13 + 1e-9; y += 0.1)
    for (double dz = -1; dz <= 8 + 1e-9; dz += 0.1) wall.emplace_back(16.5, y, plane_z(16.5, y) + dz);
  SimulateOptions o = plane_options(r, 0.02);
  const Simulation without = simulate_cut(surf, feed_centres(raster(r, s)), 0.0, o);
  const std::vector<Eigen::Vector3d> obstacles = obstacle_points(wall, surf);
  o.left_out = &obstacles;
  const Simulation with = simulate_cut(surf, feed_centres(raster(r, s)), 0.0, o);
  const double x0 = 16.5 + r * kA / 1.05 - r - 0.5 * surf.spacing();
  const auto& b = with.report["beside_left_out"];
  // (without loops the patch is the cloud's support, which reaches a little past x = 16)
  const double x1 = b["max"][0].get<double>(), band = (x1 - x0) * 12 * 1.05;
  EXPECT_NEAR(x1, 16, 0.15);
  EXPECT_NEAR(b["min"][0].get<double>(), x0, 0.05);
  EXPECT_NEAR(b["area_mm2"].get<double>(), band, 0.03 * band);
  EXPECT_NEAR(b["fraction"].get<double>(), b["area_mm2"].get<double>() / without.report["surface_area"].get<double>(), 1e-9);
  EXPECT_NEAR(with.report["surface_area"].get<double>() + b["area_mm2"].get<double>(),
              without.report["surface_area"].get<double>(), 1e-6);
  // the rest as without the wall: the raster's closed-form cusp, nothing uncut
  EXPECT_NEAR(with.report["scallop_max_interior"].get<double>(), without.report["scallop_max_interior"].get<double>(),
              1e-3);
  EXPECT_EQ(with.report["uncut_fraction"].get<double>(), 0.0);
  for (const auto& w : with.report["worst"]) EXPECT_LT(w["x"].get<double>(), x0 + 0.1) << w;
  EXPECT_FALSE(without.report.contains("beside_left_out"));
}

// A cloud known only to +-delta: the certificate's scallop and gouge are bounds for the real
// surface, the estimate's values plus delta. A raster raised 0.004 mm off the plane leaves the
// closed-form cusp + 0.004 on the estimate; with delta = 0.01 the bound is that + 0.01, and the
// gouge bound is delta - 0.004 n_z (the real surface may be up to delta higher).
TEST(Simulate, UncertainCloudGivesBoundsForTheRealSurface) {
  const double r = 3, s = 0.7, dz = 0.004, delta = 0.01;
  const auto cloud = plane_cloud();
  const std::vector<double> U(cloud.size(), delta);
  HeightFieldModel surf(cloud, 20, &U);
  EXPECT_NEAR(surf.uncertainty(7, 5), delta, 1e-15);
  EXPECT_EQ(surf.uncertainty_max(), delta);
  EXPECT_NEAR(HeightFieldModel(cloud).uncertainty(7, 5), 0.0, 1e-12);  // a plane: no misfit
  const auto res = simulate_cut(surf, feed_centres(raster(r, s, dz)), 0.0, plane_options(r, 0.05, 0.01));
  const auto& j = res.report;
  const double w = line_gap(s), cusp = r - std::sqrt(r * r - w * w / 4);
  EXPECT_NEAR(j["scallop_max_interior"].get<double>(), cusp + dz / 1.05 + delta, 0.01 * cusp);
  double gouge_interior = 0;
  for (const auto& x : res.samples)
    if (x.interior) gouge_interior = std::max(gouge_interior, x.gouge);
  EXPECT_NEAR(gouge_interior, delta - dz / 1.05, 1e-6);
  // past the outermost points the field is extrapolated and known less well: the bound grows
  // there, by 1 + (d - s/2) / (2 s) with d < 1.5 s (the patch ends there), so by at most 1.5
  EXPECT_GT(j["gouge_max"].get<double>(), gouge_interior + 0.2 * delta);
  EXPECT_LT(j["gouge_max"].get<double>(), 1.5 * delta - dz / 1.05 + 1e-6);
  EXPECT_EQ(j["surface_uncertainty_max"].get<double>(), delta);
  // at the samples: the plane's fit has no misfit; grown beyond the outermost points, < 1.5
  EXPECT_GT(j["surface_uncertainty_max_sampled"].get<double>(), 1.1 * delta);
  EXPECT_LT(j["surface_uncertainty_max_sampled"].get<double>(), 1.5 * delta);
  const std::vector<double> short_u(3, 0.0);
  try {
    HeightFieldModel bad(cloud, 20, &short_u);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "the cloud has " + std::to_string(cloud.size()) + " points but 3 uncertainties");
  }
}

// The raster moved dz in z over a plane whose points are known to 0.03 (r = 3, e = 0.01): the
// report, the sample of the largest gouge bound and the surface's uncertainty there.
struct UncertainPlaneRun {
  nlohmann::json report;
  SimSample worst;
  double gouge = 0, uncertainty = 0;
};
UncertainPlaneRun raster_over_uncertain_plane(double dz) {
  const double r = 3, s = 0.7, delta = 0.03;
  const auto cloud = plane_cloud();
  const std::vector<double> U(cloud.size(), delta);
  const HeightFieldModel surf(cloud, 20, &U);
  const auto res = simulate_cut(surf, feed_centres(raster(r, s, dz)), 0.0, plane_options(r, 0.2, 0.01));
  UncertainPlaneRun out;
  out.report = res.report;
  out.gouge = res.report["gouge_max"].get<double>();
  const auto at = std::find_if(res.samples.begin(), res.samples.end(), [&](const SimSample& x) { return x.gouge == out.gouge; });
  EXPECT_NE(at, res.samples.end());
  if (at == res.samples.end()) return out;
  out.worst = *at;
  out.uncertainty = surf.uncertainty(at->x, at->y);
  EXPECT_GE(out.uncertainty, delta);  // 0.03 inside, grown past the outermost points
  return out;
}

TEST(Simulate, AFailingBoundSaysHowMuchOfItIsTheSurfacesUncertainty) {
  // The raster lowered by 0.004 in z: the gouge on the cloud's surface is at most 0.004 n_z =
  // 0.00381, and the bound adds the uncertainty: over e = 0.01, mostly uncertainty, and the
  // reason says so, with where.
  const double dz = 0.004;
  const auto run = raster_over_uncertain_plane(-dz);
  const double gouge = run.gouge, u = run.uncertainty;
  EXPECT_GT(gouge - u, 0.0);
  EXPECT_LE(gouge - u, dz / 1.05 + 1e-9);  // the bound is the surface's gouge plus u
  char expected[400];
  std::snprintf(expected, sizeof expected,
                "gouge max %.4g > 0.01: at (%.4g, %.4g) %.4g on the cloud's surface and %.4g its uncertainty there "
                "(mostly uncertainty: a finer scan there would tighten it)",
                gouge, run.worst.x, run.worst.y, gouge - u, u);
  const auto& j = run.report;
  EXPECT_EQ(j["fail_reasons"].back(), expected);
  // the worst places carry the uncertainty their value includes
  ASSERT_FALSE(j["worst"].empty());
  EXPECT_EQ(j["worst"][0]["kind"], "gouge");
  EXPECT_NEAR(j["worst"][0]["value"].get<double>(), gouge, 1e-15);
  EXPECT_NEAR(j["worst"][0]["uncertainty"].get<double>(), u, 1e-15);
}

TEST(Simulate, ABallClearOfTheSurfaceByLessThanItsUncertaintyIsSaidSo) {
  // The raster raised by 0.004 in z: no ball touches the cloud's surface, but the bound (the
  // uncertainty less the clearance) is over e = 0.01; the reason says the ball stays clear by
  // less than the uncertainty (v10 said "0 on the cloud's surface", as if it touched).
  const double dz = 0.004;
  const auto run = raster_over_uncertain_plane(dz);
  const double gouge = run.gouge, u = run.uncertainty;
  ASSERT_GT(gouge, 0.01);
  EXPECT_GE(u - gouge, dz / 1.05 - 1e-9);  // clear of the surface by at least dz n_z
  char expected[400];
  std::snprintf(expected, sizeof expected,
                "gouge max %.4g > 0.01: at (%.4g, %.4g) the ball stays %.4g clear of the cloud's surface, less "
                "than its uncertainty there, %.4g (a finer scan there would tighten it)",
                gouge, run.worst.x, run.worst.y, u - gouge, u);
  EXPECT_EQ(run.report["fail_reasons"].back(), expected);
}

TEST(Simulate, LoweredRasterGougesByTheNormalComponent) {
  const double r = 3, s = 0.7;
  auto res = run(raster(r, s, -0.1), 0.02);
  double expect = 0.1 / 1.05;  // 0.1 in z is 0.1·n_z along the normal
  EXPECT_NEAR(res.report["gouge_max"].get<double>(), expect, 0.01 * expect);
  EXPECT_FALSE(res.report["pass"].get<bool>());
  ASSERT_FALSE(res.report["fail_reasons"].empty());
  EXPECT_EQ(res.report["worst"][0]["kind"], "gouge");
  bool found = false;
  for (const auto& f : res.report["fail_reasons"])
    found |= f.get<std::string>().rfind("gouge max 0.09", 0) == 0;
  EXPECT_TRUE(found) << res.report["fail_reasons"].dump();
}

TEST(Simulate, InteriorIsFartherThanTheMarginFromTheOutline) {
  // Every sample's interior flag, by brute force: the nearest outline node (grid nodes just
  // outside the patch) less half a spacing, against the margin sqrt(8 r h). (The simulation
  // carries a bound on that distance along each row and searches only where it does not settle
  // the answer.)
  const double r = 3, h = 0.02;
  const auto res = run(raster(r, 0.7), h);
  ASSERT_FALSE(res.outline.empty());
  const double margin = std::sqrt(8 * r * h);
  std::size_t interior = 0, checked = 0;
  for (const auto& q : res.samples) {
    double d = INFINITY;
    for (const auto& o : res.outline) d = std::min(d, (o - Eigen::Vector2d(q.x, q.y)).norm());
    const double beyond = d - 0.5 * res.spacing - margin;
    if (std::abs(beyond) < 1e-9) continue;  // on the margin, to rounding
    EXPECT_EQ(q.interior, beyond > 0) << q.x << " " << q.y;
    interior += q.interior, ++checked;
  }
  EXPECT_GT(interior, checked / 2);  // both kinds seen
  EXPECT_LT(interior, checked);
}

TEST(Simulate, RemovedPassDoublesTheGap) {
  const double r = 3, s = 0.7;
  auto res = run(raster(r, s, 0, 10), 0.02);  // pass 10 runs at y = 6
  double w = line_gap(s);
  double expect = r - std::sqrt(r * r - w * w);
  EXPECT_NEAR(res.report["scallop_max_interior"].get<double>(), expect, 0.01 * expect);
  EXPECT_FALSE(res.report["pass"].get<bool>());
}

TEST(Simulate, WideRasterWithARemovedPassLeavesUncutArea) {
  const double r = 1, s = 1.0;  // the gap left by pass 6 is about 2 r: its middle is not reached
  auto res = run(raster(r, s, 0, 6), 0.02);
  double u = res.report["uncut_fraction"].get<double>();
  EXPECT_GT(u, 0.0);
  EXPECT_LT(u, 0.2);
  EXPECT_FALSE(res.report["pass"].get<bool>());
  bool found = false;
  for (const auto& f : res.report["fail_reasons"]) found |= f.get<std::string>().rfind("uncut fraction", 0) == 0;
  EXPECT_TRUE(found);
}

TEST(Simulate, LinkedPathCentresAndRapids) {
  LinkedPath p;
  p.tool_radius = 2;
  p.moves = {{MoveKind::Rapid, {0, 0, 10}}, {MoveKind::Plunge, {0, 0, 1}}, {MoveKind::Feed, {5, 0, 1}},
             {MoveKind::Rapid, {5, 0, 10}}, {MoveKind::Rapid, {5, 4, 10}}};
  double rapid = 0;
  auto segs = feed_centres(p, rapid);
  ASSERT_EQ(segs.size(), 2u);
  EXPECT_NEAR(rapid, 13, 1e-12);
  EXPECT_NEAR((segs[1].a - Eigen::Vector3d(0, 0, 3)).norm(), 0, 1e-12);
}

// The rapids against the points: a plane z = 0 sampled every 0.1 mm, r = 2. A rapid whose ball
// stays 1 mm over it has clearance 1; one coming down to 0.01 mm into it goes through (tol
// 0.005), with the least where it ends; points raised by their uncertainty 0.3 take 0.3 off.
TEST(Simulate, TheRapidsAreCheckedAgainstThePointsRaisedByTheirUncertainty) {
  std::vector<Eigen::Vector3d> plane;
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j) plane.emplace_back(i * 0.1, j * 0.1, 0);
  const double r = 2;
  const CentreSegment over{{1, 1, r + 1}, {9, 9, r + 1}}, down{{5, 5, 20}, {5, 5, r - 0.01}};
  RapidClearance c = rapid_clearance(plane, nullptr, {over}, r, 0.005);
  EXPECT_NEAR(c.least, 1, 1e-12);
  EXPECT_EQ(c.through, 0u);
  c = rapid_clearance(plane, nullptr, {over, down}, r, 0.005);
  EXPECT_NEAR(c.least, -0.01, 1e-12);
  EXPECT_NEAR((c.at - down.b).norm(), 0, 1e-12);
  EXPECT_EQ(c.through, 1u);
  const std::vector<double> u(plane.size(), 0.3);
  EXPECT_NEAR(rapid_clearance(plane, &u, {over}, r, 0.005).least, 0.7, 1e-12);
  EXPECT_TRUE(std::isinf(rapid_clearance(plane, nullptr, {}, r, 0.005).least));
  EXPECT_THROW(rapid_clearance({}, nullptr, {over}, r, 0.005), std::invalid_argument);
  // The linked path's rapids are its rapid moves' ball centres.
  LinkedPath p;
  p.tool_radius = r;
  p.moves = {{MoveKind::Rapid, {5, 5, 20}}, {MoveKind::Rapid, {5, 5, 1}}, {MoveKind::Plunge, {5, 5, 0}},
             {MoveKind::Feed, {6, 5, 0}}, {MoveKind::Feed, {6, 5, 1}}, {MoveKind::Rapid, {6, 5, 20}}};
  double length = 0;
  std::vector<CentreSegment> rapids;
  feed_centres(p, length, &rapids);
  ASSERT_EQ(rapids.size(), 2u);
  EXPECT_NEAR((rapids[0].a - Eigen::Vector3d(5, 5, 22)).norm(), 0, 1e-12);
  EXPECT_NEAR((rapids[0].b - Eigen::Vector3d(5, 5, 3)).norm(), 0, 1e-12);
  EXPECT_NEAR(rapid_clearance(plane, nullptr, rapids, r, 0.005).least, 1, 1e-12);
}

// With a k-d tree of the unraised points at hand, the nearest raised point is the one a brute
// force finds, to the last bit: a bumpy cloud whose points are raised by 0 to 0.4 mm, a raise
// larger than their spacing, so that the nearest unraised point is often not the nearest raised
// one; rapids over it, along it, and down through it.
TEST(Simulate, TheRapidsFindTheNearestRaisedPointWithTheUnraisedPointsTree) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> cloud;
  std::vector<double> raise;
  for (int i = 0; i < 3000; ++i) {
    const double x = 10 * unit(rng), y = 10 * unit(rng);
    cloud.emplace_back(x, y, 0.5 * std::sin(x) * std::cos(1.3 * y));
    raise.push_back(0.4 * unit(rng) * unit(rng));
  }
  const PointsAdaptor<Eigen::Vector3d> adaptor{cloud};
  KdTree<Eigen::Vector3d, 3> tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const double r = 1.5, tol = 0.005;
  const std::vector<CentreSegment> rapids = {{{1, 1, 3}, {9, 8, 2.2}}, {{0, 5, 1.9}, {10, 5, 1.9}},
                                             {{4, 6, 6}, {4, 6, 0.5}}, {{-3, -3, 2}, {13, 12, 2}}};
  for (const CentreSegment& s : rapids) {
    const RapidClearance fast = rapid_clearance(cloud, &raise, tree, {s}, r, tol);
    const auto brute_nearest = [&](const Eigen::Vector3d& c) {
      double best = INFINITY;
      for (std::size_t i = 0; i < cloud.size(); ++i) {
        const Eigen::Vector3d p(cloud[i].x(), cloud[i].y(), cloud[i].z() + raise[i]);
        best = std::min(best, (c - p).squaredNorm());
      }
      return std::sqrt(best);
    };
    Eigen::Vector3d at;
    const double least = least_clearance_along(s.a, s.b, r, tol, brute_nearest, &at);
    EXPECT_EQ(fast.least, least);
    EXPECT_EQ(fast.at, at);
    EXPECT_EQ(fast.through, least < -tol ? 1u : 0u);
    // the tree built inside gives the same
    EXPECT_EQ(rapid_clearance(cloud, &raise, {s}, r, tol).least, least);
  }
  EXPECT_LT(rapid_clearance(cloud, &raise, tree, {rapids[2]}, r, tol).least, -tol);  // down through it
}

// The node's certificate counts the rapids: a linked raster over the plane z = 0 whose one way
// down ends 0.01 mm into it fails with where; the same path coming down to 1 mm over it reports
// that clearance and no such reason.
TEST(SimulateNode, ARapidThroughTheSurfaceFailsTheCertificate) {
  const NodeDecl& simulate = *builtin_registry().find("post.simulate");
  auto cloud = std::make_shared<PointCloud>();
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j) cloud->points.emplace_back(i * 0.1, j * 0.1, 0);
  auto linked = [](double down_to) {
    auto p = std::make_shared<LinkedPath>();
    p->tool_radius = 2, p->scallop_height = 0.05, p->chord_error = 0.005, p->clearance_z = 10;
    p->moves = {{MoveKind::Rapid, {0, 0, 10}}, {MoveKind::Rapid, {0, 0, down_to}}, {MoveKind::Plunge, {0, 0, 0}}};
    for (int j = 0; j <= 10; ++j) {
      p->moves.push_back({MoveKind::Feed, {j % 2 ? 10.0 : 0.0, j * 1.0, 0}});
      p->moves.push_back({MoveKind::Feed, {j % 2 ? 0.0 : 10.0, j * 1.0, 0}});
    }
    p->moves.push_back({MoveKind::Feed, {0, 10, 1}});
    p->moves.push_back({MoveKind::Rapid, {0, 10, 10}});
    return p;
  };
  auto report = [&](double down_to) {
    const auto out = test::run_node(simulate, {}, {{"linked", linked(down_to)}, {"cloud", cloud}});
    return std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  };
  const nlohmann::json through = report(-0.01);
  EXPECT_EQ(through["rapids_through_part"], 1);
  EXPECT_NEAR(through["rapid_min_clearance"].get<double>(), -0.01, 1e-12);
  EXPECT_FALSE(through["pass"].get<bool>());
  const std::string reason = "1 rapids pass through the surface (least clearance -0.01 mm at (0.000, 0.000, 1.990))";
  EXPECT_NE(std::find(through["fail_reasons"].begin(), through["fail_reasons"].end(), reason), through["fail_reasons"].end())
      << through["fail_reasons"];
  const nlohmann::json clear = report(1);
  EXPECT_EQ(clear["rapids_through_part"], 0);
  EXPECT_NEAR(clear["rapid_min_clearance"].get<double>(), 1, 1e-12);
  for (const auto& f : clear["fail_reasons"]) EXPECT_EQ(f.get<std::string>().find("rapids"), std::string::npos) << f;
}

TEST(SimulateNode, AMoveIntoWhatWasLeftOutFailsTheCertificate) {
  // The flat patch z = 0 over [0, 10]^2 and, left out beside it, a wall on x = 11 (z 0 to 5): a
  // raster whose balls (r = 2) run to x = 10 cuts 1 mm into it; one that stops at x = 8 does not.
  const NodeDecl& simulate = *builtin_registry().find("post.simulate");
  auto cloud = std::make_shared<PointCloud>(), wall = std::make_shared<PointCloud>();
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j) cloud->points.emplace_back(i * 0.1, j * 0.1, 0);
  for (int j = 0; j <= 100; ++j)
    for (int k = 0; k <= 50; ++k) wall->points.emplace_back(11, j * 0.1, k * 0.1);
  auto report = [&](double to_x) {
    auto p = std::make_shared<Toolpath>();
    p->tool_radius = 2, p->scallop_height = 0.05, p->chord_error = 0.005;
    for (int j = 0; j <= 20; ++j) {
      ToolpathPass pass;
      for (double x = 0; x <= to_x + 1e-9; x += 0.5) pass.contact.emplace_back(x, j * 0.5, 0), pass.normal.emplace_back(0, 0, 1);
      p->passes.push_back(pass);
    }
    const auto out = test::run_node(simulate, {}, {{"path", p}, {"cloud", cloud}, {"left_out", wall}});
    return std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  };
  const nlohmann::json into = report(10);
  EXPECT_FALSE(into["pass"].get<bool>());
  EXPECT_NEAR(into["left_out_min_clearance"].get<double>(), -1, 0.01);
  bool said = false;
  for (const auto& f : into["fail_reasons"])
    said |= f.get<std::string>().find(" feed moves cut into what was not machined (least clearance -1 mm at (10.000, ") !=
            std::string::npos;
  EXPECT_TRUE(said) << into["fail_reasons"];
  const nlohmann::json clear = report(8);
  EXPECT_NEAR(clear["left_out_min_clearance"].get<double>(), 1, 0.01);
  for (const auto& f : clear["fail_reasons"]) EXPECT_EQ(f.get<std::string>().find("not machined"), std::string::npos) << f;
  // no ball touching the patch beyond x = 11 - 2 - half the spacing reaches it (to the patch's
  // edge, the cloud's support a little past x = 10), 10 mm long
  const auto& b = clear["beside_left_out"];
  const double x0 = 11 - 2 - 0.5 * HeightFieldModel(cloud->points).spacing();
  EXPECT_NEAR(b["min"][0].get<double>(), x0, 0.05);
  EXPECT_NEAR(b["area_mm2"].get<double>(), (b["max"][0].get<double>() - x0) * 10, 0.3);
}

// A sparse flat patch z = 5 over [0, 40] × [0, 30] (cloud spacing 2.5 mm) and its outline
// counter-clockwise through the border points; a raster along x that covers exactly the patch.
struct SparsePatch {
  std::vector<Eigen::Vector3d> cloud;
  std::vector<Eigen::Vector2d> outline;
};
SparsePatch sparse_patch() {
  SparsePatch p;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> jitter(-0.4, 0.4);
  for (int i = 0; i <= 16; ++i)
    for (int j = 0; j <= 12; ++j) {
      bool border = i == 0 || j == 0 || i == 16 || j == 12;
      double x = 2.5 * i + (border ? 0 : jitter(rng)), y = 2.5 * j + (border ? 0 : jitter(rng));
      p.cloud.emplace_back(x, y, 5.0);
    }
  for (int i = 0; i < 16; ++i) p.outline.emplace_back(2.5 * i, 0);
  for (int j = 0; j < 12; ++j) p.outline.emplace_back(40, 2.5 * j);
  for (int i = 16; i > 0; --i) p.outline.emplace_back(2.5 * i, 30);
  for (int j = 12; j > 0; --j) p.outline.emplace_back(0, 2.5 * j);
  return p;
}

// rim_band  the band beyond the loop also counted (mm); 0: the loop's inside only.
Simulation run_sparse(double r, double s, double rim_band = 0) {
  static const SparsePatch patch = sparse_patch();
  HeightFieldModel surf(patch.cloud);
  Toolpath t;
  t.tool_radius = r;
  t.scallop_height = 0.05;
  for (double y = 0; y <= 30 + 1e-9; y += s) {
    ToolpathPass pass;
    for (double x = 0; x <= 40 + 1e-9; x += 0.5) {
      pass.contact.emplace_back(x, y, 5.0);
      pass.normal.emplace_back(0, 0, 1);
    }
    t.passes.push_back(pass);
  }
  SimulateOptions o;
  o.tool_radius = r;
  o.scallop = 0.05;
  o.spacing = 0.1;
  o.loops = {patch.outline};
  o.rim_band = rim_band;
  return simulate_cut(surf, feed_centres(t), 0.0, o);
}

TEST(Simulate, LoopsBoundTheSparsePatch) {
  const double r = 4, s = 1.25;  // 24 gaps over 30 mm
  const double expect = r - std::sqrt(r * r - s * s / 4);
  auto with = run_sparse(r, s);
  const auto& j = with.report;
  EXPECT_EQ(j["uncut_fraction"].get<double>(), 0.0);
  EXPECT_NEAR(j["scallop_max_interior"].get<double>(), expect, 0.01 * expect);
  EXPECT_NEAR(j["scallop_max"].get<double>(), expect, 0.01 * expect);
  EXPECT_LT(j["gouge_max"].get<double>(), 1e-9);
  EXPECT_NEAR(j["surface_area"].get<double>(), 40 * 30, 0.01 * 40 * 30);
  EXPECT_TRUE(j["pass"].get<bool>());
  for (const auto& q : with.samples) {
    EXPECT_TRUE(q.x >= -1e-9 && q.x <= 40 + 1e-9 && q.y >= -1e-9 && q.y <= 30 + 1e-9) << q.x << " " << q.y;
    // interior: farther than the margin sqrt(8 r h) from the square's edges
    double d = std::min({q.x, 40 - q.x, q.y, 30 - q.y});
    const double margin = std::sqrt(8 * r * 0.05);
    if (std::abs(d - margin) > 0.05) {
      EXPECT_EQ(q.interior, d > margin) << q.x << " " << q.y;
    }
  }
  // (Without loops this straight-edged patch is bounded well too, ~0.1 mm out: the guessed outline
  // overreaches on curved sparse rims such as a hemisphere's, not here.)
}

// The band beyond the loop (what the planner's band passes cut; the real outline lies beyond a
// cloud's outermost points) is counted: the square dilated by 1 mm, its corners rounded; the
// samples there are never interior. The passes stop at the loop, so the band's rim is left
// over h (1 mm out, midway between two passes, the balls of radius 4 leave 0.19) and the patch fails.
TEST(Simulate, TheRimBandBeyondTheLoopIsCounted) {
  const double r = 4;
  const auto res = run_sparse(r, 1.25, 1.0);
  const auto& j = res.report;
  EXPECT_EQ(j["rim_band"], 1.0);
  EXPECT_NEAR(j["surface_area"].get<double>(), 42 * 32 - (4 - M_PI), 0.005 * 1340);
  EXPECT_GT(j["samples_beyond_outline"].get<std::size_t>(), 0u);
  std::size_t beyond = 0;
  for (const auto& q : res.samples) {
    const double dx = std::max({-q.x, q.x - 40, 0.0}), dy = std::max({-q.y, q.y - 30, 0.0});
    // (a refinement sample, weight 0, is on the patch where its nearest grid node is)
    EXPECT_LE(std::hypot(dx, dy), 1.0 + (q.weight > 0 ? 1e-9 : 0.75 * 0.1)) << q.x << " " << q.y;
    if (dx > 0 || dy > 0) {
      ++beyond;
      EXPECT_FALSE(q.interior) << q.x << " " << q.y;
    }
  }
  EXPECT_GT(beyond, 0u);
  // the band's edge midway between two passes 1.25 apart, up to the refinement's overshoot
  const auto left = [&](double d) { return r - std::sqrt(r * r - d * d); };
  EXPECT_GE(j["scallop_max"].get<double>(), left(std::hypot(1.0, 0.625)) - 1e-3);
  EXPECT_LE(j["scallop_max"].get<double>(), left(std::hypot(1.0 + 0.75 * 0.1, 0.625)));
  EXPECT_FALSE(j["pass"].get<bool>());
  // the interior is as without the band
  const auto without = run_sparse(r, 1.25);
  EXPECT_NEAR(j["scallop_max_interior"].get<double>(), without.report["scallop_max_interior"].get<double>(), 1e-12);
}

TEST(Simulate, LoopsWithAHoleLeaveItOutButItsBand) {
  auto patch = sparse_patch();
  HeightFieldModel surf(patch.cloud);
  Toolpath t;
  t.tool_radius = 4;
  for (double y = 0; y <= 30 + 1e-9; y += 1.25) {
    ToolpathPass pass;
    for (double x = 0; x <= 40 + 1e-9; x += 0.5) pass.contact.emplace_back(x, y, 5.0), pass.normal.emplace_back(0, 0, 1);
    t.passes.push_back(pass);
  }
  SimulateOptions o;
  o.tool_radius = 4;
  o.scallop = 0.05;
  o.spacing = 0.1;
  o.loops = {patch.outline, {{10, 10}, {10, 20}, {20, 20}, {20, 10}}};  // a 10 × 10 hole
  o.rim_band = 0;
  auto res = simulate_cut(surf, feed_centres(t), 0.0, o);
  EXPECT_NEAR(res.report["surface_area"].get<double>(), 40 * 30 - 100, 0.01 * 1100);
  for (const auto& q : res.samples) EXPECT_FALSE(q.x > 10.05 && q.x < 19.95 && q.y > 10.05 && q.y < 19.95);
  // The rim band lies beyond the outer loop and 1 mm into the hole (a hole's real edge lies
  // beyond the cloud's points around it too): the hole's middle, 8 × 8, stays out of it.
  o.rim_band = 1;
  res = simulate_cut(surf, feed_centres(t), 0.0, o);
  EXPECT_NEAR(res.report["surface_area"].get<double>(), 42 * 32 - (4 - M_PI) - 64, 0.01 * 1200);
  bool in_band = false;
  for (const auto& q : res.samples) {
    EXPECT_FALSE(q.x > 11.05 && q.x < 18.95 && q.y > 11.05 && q.y < 18.95);
    in_band = in_band || (q.x > 10.05 && q.x < 10.95 && q.y > 12 && q.y < 18);
  }
  EXPECT_TRUE(in_band);
  o.loops = {{{0, 0}, {1, 1}}};
  try {
    simulate_cut(surf, feed_centres(t), 0.0, o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the outer loop has 2 points; an outline needs at least 3");
  }
}

TEST(Simulate, BadInputIsRefused) {
  auto cloud = plane_cloud();
  HeightFieldModel surf(cloud);
  SimulateOptions o;
  o.tool_radius = 3;
  o.scallop = 0.02;
  try {
    simulate_cut(surf, {}, 0, o);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the path has no feed moves");
  }
  o.tool_radius = 0;
  EXPECT_THROW(simulate_cut(surf, feed_centres(raster(3, 0.7)), 0, o), std::invalid_argument);
  try {
    HeightFieldModel tiny(std::vector<Eigen::Vector3d>(3, Eigen::Vector3d::Zero()));
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the cloud has 3 points; the surface model needs at least 10");
  }
}

}  // namespace
}  // namespace scallop
