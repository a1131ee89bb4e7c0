#include "nodes/path/gouge_guard.h"
#include "nodes/path/step_size.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nodes/all_nodes.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// The tilted plane z = 0.2 x + 0.25 y (|grad| gives sqrt(1 + 0.04 + 0.0625) = 1.05), sampled
// every 0.25 mm over [-10, 10]^2.
double plane_z(double x, double y) { return 0.2 * x + 0.25 * y; }
const Eigen::Vector3d kPlaneNormal = Eigen::Vector3d(-0.2, -0.25, 1.0) / 1.05;

std::vector<Eigen::Vector3d> plane_cloud() {
  std::vector<Eigen::Vector3d> c;
  for (double x = -10; x <= 10 + 1e-9; x += 0.25)
    for (double y = -10; y <= 10 + 1e-9; y += 0.25) c.emplace_back(x, y, plane_z(x, y));
  return c;
}

// The plane cloud with a gap at its rim: no points within `radius` of (10, 0).
std::vector<Eigen::Vector3d> plane_cloud_with_rim_gap(double radius) {
  std::vector<Eigen::Vector3d> c;
  for (const auto& p : plane_cloud())
    if (std::hypot(p.x() - 10, p.y()) > radius) c.push_back(p);
  return c;
}

// The sphere of radius R about (0, 0, -R + 5), its upper cap sampled over [-10, 10]^2.
constexpr double kR = 30;
double cap_z(double x, double y) { return std::sqrt(kR * kR - x * x - y * y) - kR + 5; }
std::vector<Eigen::Vector3d> cap_cloud() {
  std::vector<Eigen::Vector3d> c;
  for (double x = -10; x <= 10 + 1e-9; x += 0.2)
    for (double y = -10; y <= 10 + 1e-9; y += 0.2) c.emplace_back(x, y, cap_z(x, y));
  return c;
}
Eigen::Vector3d cap_point(double x, double y) { return {x, y, cap_z(x, y)}; }
Eigen::Vector3d cap_normal(double x, double y) { return (cap_point(x, y) - Eigen::Vector3d(0, 0, 5 - kR)).normalized(); }

// One pass along y at x on the plane z = 0, from y = -half to half, contacts every 0.5 mm.
Toolpath flat_pass_along_y(double x, double half, double r) {
  Toolpath t;
  t.tool_radius = r;
  t.chord_error = 0.01;
  t.scallop_height = 0.05;
  ToolpathPass p;
  for (double y = -half; y <= half + 1e-9; y += 0.5) {
    p.contact.emplace_back(x, y, 0);
    p.normal.emplace_back(0, 0, 1);
  }
  t.passes.push_back(p);
  return t;
}

// One pass along x at y on the plane, contacts every `step` mm, optionally sunk by `sink` mm
// (along the normal) at point `sunk`.
Toolpath plane_pass(double step, int sunk = -1, double sink = 0) {
  Toolpath t;
  t.tool_radius = 2;
  t.chord_error = 0.01;
  t.scallop_height = 0.05;
  ToolpathPass p;
  for (int i = 0; -5 + i * step <= 5 + 1e-9; ++i) {
    const double x = -5 + i * step;
    Eigen::Vector3d c(x, 1, plane_z(x, 1));
    if (i == sunk) c -= sink * kPlaneNormal;
    p.contact.push_back(c);
    p.normal.push_back(kPlaneNormal);
    p.uv.emplace_back(i, 0);
  }
  t.passes.push_back(p);
  return t;
}

TEST(BallClearance, IsTheDistanceToATiltedPlaneMinusR) {
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const Eigen::Vector3d foot(1, 2, plane_z(1, 2));
  for (double gap : {0.1, 0.0, -0.03}) {
    auto res = clearance(foot + (2.0 + gap) * kPlaneNormal, foot + Eigen::Vector3d(0.3, -0.2, 0));
    EXPECT_NEAR(res.clearance, gap, 1e-6) << gap;
    ASSERT_TRUE(res.on_surface);
    EXPECT_NEAR((res.foot - foot).norm(), 0, 1e-5);
    EXPECT_NEAR((res.normal - kPlaneNormal).norm(), 0, 1e-6);
  }
}

TEST(BallClearance, FindsTheNearestPlaceOnACrestTighterThanTheBall) {
  // A ridge of radius 3 (a cylinder's top, z = sqrt(9 - x^2), sampled every 0.1 mm) under a
  // ball of radius 4: the tangent-plane step overshoots by the factor 4 / 3 there, and the foot
  // search swung out onto the flank, far from the nearest place, where the ball seemed to
  // clear what it cut. Exact: the clearance is the centre's distance from the axis less 3 + 4.
  constexpr double R = 3, r = 4;
  std::vector<Eigen::Vector3d> cloud;
  for (double x = -2.5; x <= 2.5 + 1e-9; x += 0.1)
    for (double y = -5; y <= 5 + 1e-9; y += 0.1) cloud.emplace_back(x, y, std::sqrt(R * R - x * x));
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, r);
  for (double x : {0.0, 0.15, 0.4, 0.8})
    for (double gap : {0.01, -0.009}) {
      const Eigen::Vector3d axis_to_centre = Eigen::Vector3d(x, 0, std::sqrt((R + r + gap) * (R + r + gap) - x * x));
      // the hint a planner gives: the contact right under the centre
      const Eigen::Vector3d hint(x, 0, std::sqrt(R * R - x * x));
      const auto res = clearance(axis_to_centre, hint);
      ASSERT_TRUE(res.on_surface);
      EXPECT_NEAR(res.clearance, gap, 2e-4) << x << " " << gap;
      EXPECT_NEAR(res.foot.x(), R * x / (R + r + gap), 2e-3) << x << " " << gap;
    }
}

TEST(BallClearance, SeesTheCloudsPointsBeyondTheEdge) {
  // A ball beyond the cloud's edge (no height field under it) still meets the edge points.
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const Eigen::Vector3d edge(10, 0, plane_z(10, 0));
  const Eigen::Vector3d centre = edge + Eigen::Vector3d(1.0, 0, 1.0);
  auto res = clearance(centre, centre);
  EXPECT_FALSE(res.on_surface);
  double nearest = INFINITY;  // brute force over the cloud
  for (const auto& q : cloud) nearest = std::min(nearest, (q - centre).norm());
  EXPECT_LT(nearest, std::sqrt(2.0));
  EXPECT_NEAR(res.clearance, nearest - 2.0, 1e-12);
}

TEST(BallClearance, ACloudPointTheFitSmoothsAwayStillLimitsIt) {
  // One point 0.3 mm above the plane (a burr the fit over 20 neighbours mostly smooths away):
  // balls over and beside it clear it by exactly what the point itself says, the least of
  // |centre - point| - r over the points within r in xy (brute force here).
  auto cloud = plane_cloud();
  const Eigen::Vector3d burr(1, 2, plane_z(1, 2) + 0.3);
  for (auto& p : cloud)
    if ((p.head<2>() - burr.head<2>()).norm() < 1e-9) p = burr;
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  int limited_by_burr = 0;
  for (const Eigen::Vector2d offset : {Eigen::Vector2d(0, 0), Eigen::Vector2d(0.4, -0.3), Eigen::Vector2d(1.5, 0.5)})
    for (double gap : {0.03, 0.0, -0.01}) {
      const Eigen::Vector3d foot = burr + Eigen::Vector3d(offset.x(), offset.y(), 0);
      const Eigen::Vector3d centre = burr + (2.0 + gap) * kPlaneNormal + Eigen::Vector3d(offset.x(), offset.y(), 0);
      double witness = INFINITY;
      for (const auto& q : cloud)
        if ((q.head<2>() - centre.head<2>()).squaredNorm() < 4.0) witness = std::min(witness, (q - centre).norm() - 2.0);
      const auto res = clearance(centre, foot);
      ASSERT_TRUE(res.on_surface);
      EXPECT_LE(res.clearance, witness);
      if (witness < res.clearance + 1e-12) {
        EXPECT_EQ(res.clearance, witness) << offset.transpose() << " " << gap;
        ++limited_by_burr;
      }
    }
  EXPECT_GE(limited_by_burr, 6);  // the burr, not the fit, decides those over and near it
}

TEST(BallClearance, CoversTheEdgeBandAndGapsAtTheRim) {
  // The part's edge lies about half a spacing beyond a cloud's outermost points: a foot there is
  // on the surface (the field extrapolated), one farther out is not. A foot in a gap the sample
  // left at the rim (here no points within 0.45 mm of (10, 0)) is on the surface up to two
  // spacings from the nearest point, as long as it is not past the rim's other points.
  const auto cloud = plane_cloud_with_rim_gap(0.45);
  HeightFieldModel surface(cloud);
  const double s = surface.spacing();
  BallClearance clearance(surface, cloud, 2.0);
  auto on_surface = [&](double x, double y) {
    const Eigen::Vector3d foot(x, y, plane_z(x, y));
    auto res = clearance(foot + 1.95 * kPlaneNormal, foot);
    if (res.on_surface) EXPECT_NEAR(res.clearance, -0.05, 1e-6) << x << " " << y;
    return res.on_surface;
  };
  EXPECT_TRUE(on_surface(10.1, 5));    // half a spacing past a straight rim
  EXPECT_FALSE(on_surface(10.4, 5));   // nearest point 0.4 > s = 0.22, past the rim
  EXPECT_FALSE(on_surface(11.0, 5));
  // in the gap: the nearest point, (9.5, 0), is 0.35 mm away, between s and 2 s
  EXPECT_TRUE(s < 0.35 && 0.35 < 2 * s) << s;
  EXPECT_TRUE(on_surface(9.85, 0));
  EXPECT_FALSE(on_surface(10.4, 0));  // past the rim beside the gap
}

TEST(BallClearance, WithAnOutlineCoversEveryGapInsideIt) {
  // A gap at the rim wider than the band kept without an outline (no points within 1.2 mm of
  // (10, 0): a foot at (9.4, 0) is 0.6 mm > 2 spacings from the nearest point). post.simulate
  // certifies everything inside the boundary loops' outline, so given that outline the guard
  // checks the (extrapolated) field there too; past the outline it still does not.
  const auto cloud = plane_cloud_with_rim_gap(1.2);
  HeightFieldModel surface(cloud);
  ASSERT_LT(2 * surface.spacing(), 0.6);
  const Outline outline({{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}});
  BallClearance without(surface, cloud, 2.0), with(surface, cloud, 2.0, &outline);
  auto probe = [&](const BallClearance& c, double x, double y) {
    const Eigen::Vector3d foot(x, y, plane_z(x, y));
    return c(foot + 1.95 * kPlaneNormal, foot);
  };
  EXPECT_FALSE(probe(without, 9.4, 0).on_surface);
  const auto in_gap = probe(with, 9.4, 0);
  ASSERT_TRUE(in_gap.on_surface);
  EXPECT_NEAR(in_gap.clearance, -0.05, 1e-6);  // the plane, extrapolated exactly
  EXPECT_FALSE(probe(with, 10.4, 0).on_surface);
  // With a rim band (what the planner's band passes cut and the certificate counts) the field
  // is checked out to its width beyond the outline.
  BallClearance with_band(surface, cloud, 2.0, &outline, nullptr, 0.5);
  const auto in_band = probe(with_band, 10.4, 0);
  ASSERT_TRUE(in_band.on_surface);
  EXPECT_NEAR(in_band.clearance, -0.05, 1e-6);
  EXPECT_FALSE(probe(with_band, 10.6, 0).on_surface);
}

TEST(BallClearance, InAGapAtTheRimTheBandIsCheckedAroundTheFoot) {
  // The plane known to +-0.02 with a gap at its rim (no points within 1.2 mm of (10, 0)), given
  // the square outline: in the gap the field's uncertainty grows with the distance from the
  // points, outward faster than a ball's distance from the plane grows from its foot. A ball
  // clearing the band at its foot (9.6, 0) by exactly its uncertainty there reaches deeper into
  // it a few tenths of a mm outward; the certificate samples those places, so the clearance
  // must see them: its reach is within 0.002 of the deepest over a 0.02 mm grid of the gap
  // (what the certificate would find), not the foot's 0.
  const auto cloud = plane_cloud_with_rim_gap(1.2);
  const std::vector<double> uncertainty(cloud.size(), 0.02);
  HeightFieldModel surface(cloud, 20, &uncertainty);
  const Outline outline({{{-10, -10}, {10, -10}, {10, 10}, {-10, 10}}});
  BallClearance clearance(surface, cloud, 2.0, &outline);
  const Eigen::Vector3d foot(9.6, 0, plane_z(9.6, 0));
  const double u_foot = surface.uncertainty(9.6, 0);
  const Eigen::Vector3d c = foot + (2.0 + u_foot) * kPlaneNormal;
  const auto x = clearance(c, foot);
  ASSERT_TRUE(x.on_surface);
  EXPECT_NEAR(x.foot_reach(), 0, 1e-6);
  double deepest = -INFINITY;
  for (double qx = 8.6; qx <= 10 + 1e-9; qx += 0.02)
    for (double qy = -1; qy <= 1 + 1e-9; qy += 0.02) {
      double z, u;
      Eigen::Vector3d n;
      surface.eval(qx, qy, z, n, true, &u);
      deepest = std::max(deepest, u - ((c - Eigen::Vector3d(qx, qy, z)).norm() - 2.0));
    }
  EXPECT_GT(deepest, 0.004);
  EXPECT_TRUE(x.band_is_deepest());
  EXPECT_LE(x.reach(), deepest + 1e-9);
  EXPECT_GT(x.reach(), deepest - 0.002);
}

TEST(GougeGuard, LeavesAPathOnTheSurfaceAlone) {
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const Toolpath path = plane_pass(0.5);
  auto res = guard_gouges(path, clearance, {});
  ASSERT_EQ(res.path.passes[0].contact.size(), path.passes[0].contact.size());
  for (std::size_t i = 0; i < path.passes[0].contact.size(); ++i)
    EXPECT_EQ(res.path.passes[0].contact[i], path.passes[0].contact[i]);
  EXPECT_EQ(res.report["lifted_positions"], 0);
  EXPECT_EQ(res.report["inserted_positions"], 0);
  EXPECT_EQ(res.report["positions_checked"], 21);
  EXPECT_EQ(res.report["moves_checked"], 20);
  EXPECT_TRUE(res.report["warnings"].empty());
}

TEST(GougeGuard, LiftsAPositionThatCutsInUntilTheBallTouches) {
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  // point 10 sunk 0.05 mm into the plane: more than the tolerance e/4 = 0.0025
  const Toolpath path = plane_pass(0.5, 10, 0.05);
  auto res = guard_gouges(path, clearance, {});
  const auto& p = res.path.passes[0];
  ASSERT_EQ(p.contact.size(), path.passes[0].contact.size());
  // lifted along z back onto the plane: the ball centre is r above it along the normal again
  const Eigen::Vector3d c = res.path.centre(p.contact[10], p.normal[10]);
  EXPECT_NEAR(c.z() - plane_z(c.x(), c.y()), 2.0 / kPlaneNormal.z(), 1e-6);
  EXPECT_NEAR((p.normal[10] - kPlaneNormal).norm(), 0, 1e-6);
  EXPECT_NEAR(clearance(res.path.centre(p.contact[10], p.normal[10]), p.contact[10]).clearance, 0, 1e-6);
  EXPECT_EQ(res.report["lifted_positions"], 1);
  EXPECT_NEAR(res.report["deepest_cut_in"].get<double>(), 0.05, 1e-6);
  // the lift is along z: 0.05 / n_z
  EXPECT_NEAR(res.report["highest_lift"].get<double>(), 0.05 / kPlaneNormal.z(), 1e-6);
  ASSERT_EQ(res.report["warnings"].size(), 1u);
  EXPECT_EQ(res.report["warnings"][0].get<std::string>().rfind("1 tool positions (0 of them added in the middle of moves) were lifted by up to 0.0525 mm", 0), 0u);
  // a sink within the tolerance stays
  auto small = guard_gouges(plane_pass(0.5, 10, 0.002), clearance, {});
  EXPECT_EQ(small.report["lifted_positions"], 0);
}

TEST(GougeGuard, LiftedBallsClearAnUncertainSurfaceByItsUncertainty) {
  // every point known to +-0.01 mm: a lifted ball clears the estimate by 0.01, so a real surface
  // 0.01 higher is touched, not cut
  auto cloud = plane_cloud();
  const std::vector<double> uncertainty(cloud.size(), 0.01);
  HeightFieldModel surface(cloud, 20, &uncertainty);
  BallClearance clearance(surface, cloud, 2.0);
  // planned with 0.01 of stock (the planner's margin), one position sunk 0.05 below the surface
  auto planned = plane_pass(0.5, 10, 0.06);
  for (auto& c : planned.passes[0].contact) c += 0.01 * kPlaneNormal;
  auto res = guard_gouges(planned, clearance, {});
  const auto& p = res.path.passes[0];
  const auto after = clearance(res.path.centre(p.contact[10], p.normal[10]), p.contact[10]);
  EXPECT_NEAR(after.uncertainty, 0.01, 1e-12);
  EXPECT_NEAR(after.clearance, 0.01, 1e-6);
  EXPECT_EQ(res.report["lifted_positions"], 1);
  EXPECT_NEAR(res.report["deepest_cut_in"].get<double>(), 0.06, 1e-6);
  EXPECT_NEAR(res.report["highest_lift"].get<double>(), 0.06 / kPlaneNormal.z(), 1e-6);
  // planned touching the estimate, every ball reaches 0.01 into the band and is lifted
  EXPECT_EQ(guard_gouges(plane_pass(0.5), clearance, {}).report["lifted_positions"], 21);

  // What the planner keeps for delta = e = 0.01 (chord_budget): the gouge budget is 0.9 e - 0.15
  // delta = 0.0075, the overcut e/4, so the stock is 0.005 and its balls reach 0.005 into the
  // band. The guard lets them be, and lifts a ball that reaches in more than e/4 beyond that.
  EXPECT_NEAR(gouge_budget(0.01, 0.01), 0.0075, 1e-15);
  const ChordBudget budget = chord_budget(0.01, 0.01);
  EXPECT_NEAR(budget.stock, 0.005, 1e-15);
  EXPECT_NEAR(budget.reach, 0.005, 1e-15);
  EXPECT_NEAR(budget.overcut + 0.01 - budget.stock, 0.0075, 1e-15);
  auto with_stock = [&](double stock) {
    auto path = plane_pass(0.5);
    for (auto& c : path.passes[0].contact) c += stock * kPlaneNormal;
    return path;
  };
  EXPECT_EQ(guard_gouges(with_stock(budget.stock), clearance, {}).report["lifted_positions"], 0);
  EXPECT_EQ(guard_gouges(with_stock(budget.stock - 0.0024), clearance, {}).report["lifted_positions"], 0);
  EXPECT_EQ(guard_gouges(with_stock(budget.stock - 0.0026), clearance, {}).report["lifted_positions"], 21);
  // a tolerance given is the tolerance everywhere
  GougeGuardOptions strict;
  strict.tolerance = 0.001;
  EXPECT_EQ(guard_gouges(with_stock(budget.stock), clearance, strict).report["lifted_positions"], 21);
  // on a clean cloud (delta 0) nothing is added to e/4
  EXPECT_NEAR(chord_budget(0.01, 0).reach, 0, 1e-15);
  EXPECT_NEAR(chord_budget(0.01, 0).overcut, 0.009, 1e-15);
}

TEST(GougeGuard, ABallBesideAMoreUncertainStretchClearsItToo) {
  // The plane z = 0 sampled every 0.25 mm, its points known exactly for x < 0.7 and to +-0.3 mm
  // from there on. A ball of radius 10 planned touching the plane at x = 0: its foot point's 20
  // nearest points (|dx| <= 0.5) are all exact, so the band there is the plane itself and the
  // foot alone would pass it. But the fit over x >= 1.25 is known only to 0.3 (every neighbour
  // beyond 0.7), and the ball's centre is sqrt(1.25^2 + 10^2) - 10 = 0.0778 mm farther from
  // there than its radius: it reaches 0.2222 mm into that band, and is lifted until it clears
  // it, to sqrt(10.3^2 - 1.25^2) = 10.2239 above the plane (a crest's flank beside its top,
  // where a flattened fit is least certain, the way a 50 000-point cloud of a 1 mm crest had it).
  std::vector<Eigen::Vector3d> cloud;
  std::vector<double> uncertainty;
  for (double x = -10; x <= 10 + 1e-9; x += 0.25)
    for (double y = -10; y <= 10 + 1e-9; y += 0.25) {
      cloud.emplace_back(x, y, 0);
      uncertainty.push_back(x >= 0.7 ? 0.3 : 0.0);
    }
  HeightFieldModel surface(cloud, 20, &uncertainty);
  constexpr double r = 10;
  BallClearance clearance(surface, cloud, r);
  const auto at = clearance(Eigen::Vector3d(0, 0, r), Eigen::Vector3d(0, 0, 0));
  ASSERT_TRUE(at.on_surface);
  EXPECT_NEAR(at.uncertainty, 0, 1e-12);
  EXPECT_NEAR(at.clearance, 0, 1e-9);
  EXPECT_NEAR(at.band_reach, 0.3 - (std::hypot(1.25, r) - r), 1e-9);
  EXPECT_NEAR(at.band_up, r / std::hypot(1.25, r), 1e-9);

  const Toolpath planned = flat_pass_along_y(0, 5, r);
  const ToolpathPass& pass = planned.passes[0];
  auto res = guard_gouges(planned, clearance, {});
  EXPECT_EQ(res.report["lifted_positions"], pass.contact.size());
  const auto& q = res.path.passes[0];
  ASSERT_EQ(q.contact.size(), pass.contact.size());  // the moves along y stay level: none split
  for (std::size_t i = 0; i < q.contact.size(); ++i) {
    const Eigen::Vector3d c = res.path.centre(q.contact[i], q.normal[i]);
    // (the lift's linear steps overshoot a distance that grows faster than linearly: never short)
    EXPECT_GE(c.z(), std::sqrt(10.3 * 10.3 - 1.25 * 1.25) - 1e-6) << i;
    EXPECT_LE(c.z(), std::sqrt(10.3 * 10.3 - 1.25 * 1.25) + 1e-4) << i;
    // every exactly 0.3-uncertain place of the plane (x >= 1.25) is cleared by 0.3
    double least = INFINITY;
    for (std::size_t j = 0; j < cloud.size(); ++j)
      if (cloud[j].x() >= 1.25 - 1e-9) least = std::min(least, (c - cloud[j]).norm() - r);
    EXPECT_GE(least, 0.3 - 1e-6) << i;
  }
}

TEST(GougeGuard, BeyondTheCloudsEdgeTheExtrapolationIsLessCertain) {
  // A ball whose foot lies 0.2 mm beyond the last points of a cloud known to +-0.05 must clear
  // the extrapolated plane by 0.05 (1 + (0.2 - spacing / 2) / (2 spacing)); a ball planned with the
  // interior's 0.05 of stock there is lifted. On and inside the last points nothing grows.
  auto cloud = plane_cloud();
  const std::vector<double> uncertainty(cloud.size(), 0.05);
  HeightFieldModel surface(cloud, 20, &uncertainty);
  const double s = surface.spacing(), grown = 0.05 * (1 + (0.2 - 0.5 * s) / (2 * s));
  for (double x : {5.0, 9.9, 10.0}) EXPECT_NEAR(surface.uncertainty(x, 0), 0.05, 1e-12) << x;
  EXPECT_NEAR(surface.uncertainty(10.2, 0), grown, 1e-9);
  BallClearance clearance(surface, cloud, 2.0);
  Toolpath planned = plane_pass(0.5);
  auto& p = planned.passes[0];
  for (std::size_t i = 0; i < p.contact.size(); ++i) {
    const double y = p.contact[i].x() / 10;
    p.contact[i] = Eigen::Vector3d(10.2, y, plane_z(10.2, y)) + 0.05 * kPlaneNormal;
  }
  const auto before = clearance(planned.centre(p.contact[5], p.normal[5]), p.contact[5]);
  ASSERT_TRUE(before.on_surface);
  EXPECT_NEAR(before.clearance, 0.05, 1e-6);
  EXPECT_NEAR(before.uncertainty, grown, 1e-6);
  // (the moves held to 0.9 e: the gouge budget for this uncertainty, 0.9 e - 0.15 * 0.06, is
  // about 0, and the positions are what this is about)
  GougeGuardOptions moves_loose;
  moves_loose.chord_tolerance = 0.009;
  auto res = guard_gouges(planned, clearance, moves_loose);
  EXPECT_EQ(res.report["lifted_positions"], p.contact.size());
  const auto& q = res.path.passes[0];
  const auto after = clearance(res.path.centre(q.contact[5], q.normal[5]), q.contact[5]);
  // clears the band, by no more than the lift moves the foot (and so the band) along
  EXPECT_GE(after.clearance, after.uncertainty - 1e-6);
  EXPECT_NEAR(after.clearance, grown, 5e-4);
}

// A pass of a ball of radius 2 (e = 0.01) on the cap through contacts at x = xs (y = 0), each
// raised `above` along its normal.
Toolpath cap_pass(const std::vector<double>& xs, double above = 0) {
  Toolpath path;
  path.tool_radius = 2;
  path.chord_error = 0.01;
  ToolpathPass p;
  for (double x : xs) {
    p.normal.push_back(cap_normal(x, 0));
    p.contact.push_back(cap_point(x, 0) + above * p.normal.back());
  }
  path.passes.push_back(p);
  return path;
}
// One move on the cap between contacts at x = -half and half.
Toolpath cap_move(double half, double above = 0) { return cap_pass({-half, half}, above); }

// How far a ball centred at c reaches into the cap's exact sphere raised by delta (mm).
double cap_band_reach(const Eigen::Vector3d& c, double delta) {
  return delta - ((c - Eigen::Vector3d(0, 0, 5 - kR)).norm() - kR - 2.0);
}
// The deepest cap_band_reach along every move of the path's first pass (101 places per move).
double deepest_along_moves(const Toolpath& path, double delta) {
  const auto& q = path.passes[0];
  double deepest = -INFINITY;
  for (std::size_t i = 0; i + 1 < q.contact.size(); ++i) {
    const Eigen::Vector3d a = path.centre(q.contact[i], q.normal[i]);
    const Eigen::Vector3d b = path.centre(q.contact[i + 1], q.normal[i + 1]);
    for (int j = 0; j <= 100; ++j) deepest = std::max(deepest, cap_band_reach(a + (b - a) * (j / 100.0), delta));
  }
  return deepest;
}

// Contacts 8 mm apart: the straight centre move sags about 8^2 / (8 (30 + 2)) = 0.25 mm into the sphere.
Toolpath cap_move_8mm() { return cap_move(4.0); }

TEST(GougeGuard, SplitsAMoveWhoseMiddleCutsIn) {
  // Two contacts 8 mm apart on a sphere of radius 30: the straight centre move sags by about
  // 8^2 / (8 (30 + 2)) = 0.25 mm into it; the guard inserts lifted points until every move's
  // quarter points are within the chord tolerance.
  auto cloud = cap_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const Toolpath path = cap_move_8mm();
  GougeGuardOptions o;
  o.max_splits = 8;
  auto res = guard_gouges(path, clearance, o);
  const auto& q = res.path.passes[0];
  EXPECT_GT(q.contact.size(), 2u);
  EXPECT_EQ(res.report["inserted_positions"].get<std::size_t>(), q.contact.size() - 2);
  EXPECT_EQ(res.report["unresolved"], 0);
  EXPECT_GT(res.report["deepest_cut_in"].get<double>(), 0.2);
  for (std::size_t i = 0; i + 1 < q.contact.size(); ++i) {
    const Eigen::Vector3d a = res.path.centre(q.contact[i], q.normal[i]);
    const Eigen::Vector3d b = res.path.centre(q.contact[i + 1], q.normal[i + 1]);
    for (double f : {0.0, 0.25, 0.5, 0.75}) {
      const Eigen::Vector3d c = (1 - f) * a + f * b;
      // exact distance to the sphere minus r
      const double cl = (c - Eigen::Vector3d(0, 0, 5 - kR)).norm() - kR - 2.0;
      EXPECT_GT(cl, -0.009 - 1e-4) << i << " " << f;
    }
  }
}

TEST(GougeGuard, APointInsertedIntoAMoveIsRaisedOnlyToThreeQuartersOfTheTolerance) {
  // A move on the clean cap whose straight centre chord sags 0.0095 mm into the sphere in its
  // middle (centres on the sphere of radius 32 at angles +-acos(1 - 0.0095 / 32)): just over the
  // chord tolerance 0.9 e = 0.009. One point is inserted there, raised until it reaches in by
  // 0.75 * 0.009 = 0.00675, not to touch the sphere (0.0095 higher: the cusps beside such a point
  // then rose by about half that, more than the planner had planned for).
  auto cloud = cap_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const double half = kR * std::sin(std::acos(1 - 0.0095 / 32));
  const Toolpath path = cap_move(half);
  const ToolpathPass& p = path.passes[0];
  const Eigen::Vector3d a0 = path.centre(p.contact[0], p.normal[0]), b0 = path.centre(p.contact[1], p.normal[1]);
  EXPECT_NEAR(cap_band_reach(0.5 * (a0 + b0), 0), 0.0095, 1e-9);
  auto res = guard_gouges(path, clearance, {});
  EXPECT_EQ(res.report["inserted_positions"], 1);
  EXPECT_EQ(res.report["lifted_positions"], 1);
  EXPECT_EQ(res.report["unresolved"], 0);
  const auto& q = res.path.passes[0];
  ASSERT_EQ(q.contact.size(), 3u);
  const Eigen::Vector3d m = res.path.centre(q.contact[1], q.normal[1]);
  EXPECT_NEAR(cap_band_reach(m, 0), 0.00675, 1e-4);
  EXPECT_NEAR(m.z() - 0.5 * (a0.z() + b0.z()), 0.0095 - 0.00675, 1e-4);
  EXPECT_NEAR((m - 0.5 * (a0 + b0)).head<2>().norm(), 0, 1e-9);
  EXPECT_LE(deepest_along_moves(res.path, 0), 0.009);
}

TEST(GougeGuard, AMoveTheHalvingsCannotClearIsRaisedWhole) {
  // The move of SplitsAMoveWhoseMiddleCutsIn with no halving allowed: its middle sags about
  // 0.25 mm into the sphere; both ends are raised until every probe is within the chord
  // tolerance, and then the whole straight move clears the exact sphere by the same (its
  // deepest place is the middle, a probe). Raised balls never come nearer a surface below.
  auto cloud = cap_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  const Toolpath path = cap_move_8mm();
  const ToolpathPass& p = path.passes[0];
  GougeGuardOptions o;
  o.max_splits = 0;
  auto res = guard_gouges(path, clearance, o);
  EXPECT_EQ(res.report["raised_moves"], 1);
  EXPECT_EQ(res.report["unresolved"], 0);
  EXPECT_EQ(res.report["inserted_positions"], 0);
  const auto& q = res.path.passes[0];
  ASSERT_EQ(q.contact.size(), 2u);
  const Eigen::Vector3d a = res.path.centre(q.contact[0], q.normal[0]), b = res.path.centre(q.contact[1], q.normal[1]);
  // both ends raised by the same, at least what the middle sagged less the tolerance
  const Eigen::Vector3d a0 = path.centre(p.contact[0], p.normal[0]), b0 = path.centre(p.contact[1], p.normal[1]);
  EXPECT_NEAR(a.z() - a0.z(), b.z() - b0.z(), 1e-12);
  EXPECT_NEAR((a - a0).head<2>().norm(), 0, 1e-12);
  double least = INFINITY;
  for (int i = 0; i <= 400; ++i) {
    const Eigen::Vector3d c = a + (b - a) * (i / 400.0);
    least = std::min(least, (c - Eigen::Vector3d(0, 0, 5 - kR)).norm() - kR - 2.0);
  }
  EXPECT_GT(least, -0.009 - 1e-4);
  EXPECT_LT(least, 0.01);  // raised to the tolerance, not far beyond
  EXPECT_GT(res.report["highest_lift"].get<double>(), 0.2);
}

TEST(GougeGuard, AMoveOverAnUncertainSurfaceIsHeldToTheGougeBudget) {
  // The cap's points known to +-0.02 (more than e = 0.01): the gouge budget is 0.9 e - 0.15 *
  // 0.02 = 0.006 (what the certificate's uncertainty, sampled between the places checked, leaves
  // of 0.9 e). A ball of radius 2 kept 0.016 above the sphere at both ends of a move 1.012 mm long
  // reaches 0.02 - 0.016 = 0.004 into the band there (no lift: within the budget), and its centre
  // chord, 1.08 mm long on the sphere of centres (radius 32.016), sags 1.08^2 / (8 * 32.016) =
  // 0.0046 below it, so the middle reaches 0.0086 in: more than the budget, less than 0.9 e. A point is inserted, and then every probe
  // clears the exact sphere raised by 0.02 to within the budget; held to 0.9 e, none is.
  auto cloud = cap_cloud();
  const std::vector<double> uncertainty(cloud.size(), 0.02);
  HeightFieldModel surface(cloud, 20, &uncertainty);
  BallClearance clearance(surface, cloud, 2.0);
  const Toolpath path = cap_move(0.506, 0.016);
  const ToolpathPass& p = path.passes[0];
  auto reach = [&](const Eigen::Vector3d& c) { return cap_band_reach(c, 0.02); };
  const Eigen::Vector3d a0 = path.centre(p.contact[0], p.normal[0]), b0 = path.centre(p.contact[1], p.normal[1]);
  EXPECT_NEAR(reach(a0), 0.004, 1e-9);
  EXPECT_NEAR(reach(0.5 * (a0 + b0)), 0.0086, 1e-4);
  auto res = guard_gouges(path, clearance, {});
  EXPECT_EQ(res.report["lifted_positions"], 1);  // the inserted point
  EXPECT_EQ(res.report["inserted_positions"], 1);
  EXPECT_DOUBLE_EQ(res.report["chord_tolerance"].get<double>(), 0.009);
  EXPECT_EQ(res.report["chord_tolerance_less_uncertainty"], true);
  EXPECT_LE(deepest_along_moves(res.path, 0.02), 0.006 + 1e-4);
  GougeGuardOptions loose;
  loose.chord_tolerance = 0.009;
  EXPECT_EQ(guard_gouges(path, clearance, loose).report["inserted_positions"], 0);
}

TEST(GougeGuard, WhereTheSurfaceIsKnownWorseThanSixEBallsAndMovesAreHeldClearOfIt) {
  // The cap's points known to +-0.08: the gouge budget 0.9 e - 0.15 * 0.08 = -0.003 is a
  // clearance. Balls planned touching the band (0.08 above the sphere), contacts 1.2 mm apart
  // (the centre chord sags 1.2^2 / (8 * 32.08) = 0.0056 more): every position is lifted clear of
  // the band by 1.5 times that clearance, and every move, halved or raised whole, ends up
  // clearing it by at least 0.003 along its whole length; nothing left unresolved. (Lifted and
  // raised only to the clearance itself, the moves were halved to the end and raised forever.)
  auto cloud = cap_cloud();
  const std::vector<double> uncertainty(cloud.size(), 0.08);
  HeightFieldModel surface(cloud, 20, &uncertainty);
  BallClearance clearance(surface, cloud, 2.0);
  const double budget = gouge_budget(0.01, 0.08);
  ASSERT_NEAR(budget, -0.003, 1e-12);
  const Toolpath path = cap_pass({-3, -1.8, -0.6, 0.6, 1.8, 3}, 0.08);
  for (int splits : {3, 0}) {
    GougeGuardOptions o;
    o.max_splits = splits;
    auto res = guard_gouges(path, clearance, o);
    EXPECT_EQ(res.report["unresolved"], 0) << splits;
    EXPECT_GE(res.report["lifted_positions"].get<std::size_t>(), 6u) << splits;
    EXPECT_LT(res.report["highest_lift"].get<double>(), 0.02) << splits;  // no more than it needs
    EXPECT_LE(deepest_along_moves(res.path, 0.08), budget + 2e-4) << splits;
  }
}

TEST(GougeGuard, BadInputGetsClearErrors) {
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  Toolpath empty;
  empty.tool_radius = 2;
  try {
    guard_gouges(empty, clearance, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the tool path has no points");
  }
  Toolpath bad = plane_pass(1.0);
  bad.passes[0].normal.pop_back();
  try {
    guard_gouges(bad, clearance, {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "a pass has 11 points but 10 normals");
  }
  std::vector<Eigen::Vector3d> none;
  EXPECT_THROW(BallClearance(surface, none, 2.0), std::invalid_argument);
  EXPECT_THROW(BallClearance(surface, cloud, 0.0), std::invalid_argument);
}

TEST(GougeGuard, ALiftOfMoreThanThreeToolRadiiFailsWithWhereAndWhy) {
  // r = 2: a position sunk 5.8 mm needs a lift of 5.8 / n_z = 6.09 mm > 6 mm; one sunk 5.6 mm
  // (5.88 mm) is still lifted.
  auto cloud = plane_cloud();
  HeightFieldModel surface(cloud);
  BallClearance clearance(surface, cloud, 2.0);
  auto ok = guard_gouges(plane_pass(0.5, 10, 5.6), clearance, {});
  EXPECT_NEAR(ok.report["highest_lift"].get<double>(), 5.6 / kPlaneNormal.z(), 1e-6);
  // the planned ball centre: contact (0, 1, 0.25) sunk 5.8 along the normal, plus r along it
  const Eigen::Vector3d centre = Eigen::Vector3d(0, 1, 0.25) - 3.8 * kPlaneNormal;
  EXPECT_NEAR(centre.x(), 0.7238, 1e-4);
  const auto failure = [](const BallClearance& c) {
    try {
      guard_gouges(plane_pass(0.5, 10, 5.8), c, {});
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("no failure");
  };
  const std::string lift =
      "the planned ball at (0.7238, 1.905, -3.369) would have to be lifted by 6.09 mm (> 3 tool radii, 6 mm) to "
      "clear the cloud's surface: ";
  EXPECT_EQ(failure(clearance), lift + "the plan does not follow the surface there, e.g. a fold-over of the (u,v) map");
  // Where the ball reaches beyond the patch's outline (here x = 1), the field under it is only
  // extrapolated: a floor beside a steep wall that the trim cut off was refused with the
  // fold-over alone named (a 10 mm wall: a lift of 42.65 mm, the field extrapolated over it).
  const Outline outline({{{-10, -10}, {1, -10}, {1, 10}, {-10, 10}}});
  EXPECT_EQ(failure(BallClearance(surface, cloud, 2.0, &outline)),
            lift + "the ball reaches 1.724 mm beyond the patch's outline, where the surface is only extrapolated "
                   "from the cloud's points: a region left out beside the patch rises there (a steep wall "
                   "cloud.trim_steep cut off beside a floor, say), or the plan does not follow the surface there, "
                   "e.g. a fold-over of the (u,v) map");
}

// Floor z = 0 sampled every 0.25 mm over x in [x_from, x_to], |y| <= 6; walls the trim left out,
// points every 0.25 mm on the planes x = each of wall_x, from z = 0.25 up to z = 6.
struct FloorAndWalls {
  std::vector<Eigen::Vector3d> floor, walls;
  FloorAndWalls(double x_from, double x_to, std::initializer_list<double> wall_x) {
    for (double x = x_from; x <= x_to + 1e-9; x += 0.25)
      for (double y = -6; y <= 6 + 1e-9; y += 0.25) floor.emplace_back(x, y, 0);
    for (double wx : wall_x)
      for (double z = 0.25; z <= 6 + 1e-9; z += 0.25)
        for (double y = -6; y <= 6 + 1e-9; y += 0.25) walls.emplace_back(wx, y, z);
  }
};

TEST(GougeGuard, ABallBesideAWallTheTrimLeftOutIsMovedOffItAndSetDownOnTheFloor) {
  // A floor to x = 4 and beside it a wall on x = 4.2. A pass along y at x = 2.5, the ball (r = 2)
  // on the floor, 1.7 mm from the wall: it must clear the wall's points by r + half the floor's
  // spacing (0.2216 as the height field measures it), 2.1108. Lifted, it rode over the wall's
  // top at z = 7.25 and left the floor beside the wall uncut; moved sideways it finishes the floor
  // up to x = 4.2 - 2.1108: its centre at (2.0892, y, 2), touching the floor.
  const FloorAndWalls part(-6, 4, {4.2});
  const Toolpath t = flat_pass_along_y(2.5, 3, 2.0);
  HeightFieldModel surface(part.floor);
  const double clear = 2 + 0.5 * surface.spacing();
  EXPECT_NEAR(4.2 - clear, 2.0892, 1e-4);
  // without the wall the floor asks for nothing
  EXPECT_EQ(guard_gouges(t, BallClearance(surface, part.floor, 2.0), {}).report["lifted_positions"], 0);
  const auto res = guard_gouges(t, BallClearance(surface, part.floor, 2.0, nullptr, nullptr, 0, &part.walls), {});
  EXPECT_EQ(res.report["pushed_off_left_out"], t.passes[0].contact.size());
  EXPECT_EQ(res.report["lifted_positions"], 0);
  for (std::size_t i = 0; i < res.path.passes[0].contact.size(); ++i) {
    const Eigen::Vector3d c = res.path.passes[0].contact[i] + 2.0 * res.path.passes[0].normal[i];
    EXPECT_NEAR(c.x(), 4.2 - clear, 2e-4) << i;
    EXPECT_NEAR(c.y(), t.passes[0].contact[i].y(), 1e-9) << i;
    EXPECT_NEAR(c.z(), 2, 1e-6) << i;  // on the floor
    for (const auto& w : part.walls) EXPECT_GE((c - w).norm(), clear - 1e-9);
  }
}

TEST(GougeGuard, ABallInASlotNarrowerThanItIsLiftedJustClearOfBothWalls) {
  // Walls on x = 0.8 and 4.2, the floor between: a ball (r = 2) at x = 2.5 is 1.7 mm from each,
  // and moved off one it meets the other. Lifted, its centre must clear both walls' top rows by
  // 2.1108: z = 6 + sqrt(2.1108^2 - 1.7^2) = 7.2512. Lifted in steps of reach / rate, with the
  // rate 0.2 where the wall's points lie level with the centre, the last step overshot: by
  // 6.14 mm, over 3 tool radii, and the pass was refused; the step is halved back.
  const FloorAndWalls part(1, 4, {0.8, 4.2});
  const Toolpath t = flat_pass_along_y(2.5, 3, 2.0);
  HeightFieldModel surface(part.floor);
  const double clear = 2 + 0.5 * surface.spacing();
  const auto res = guard_gouges(t, BallClearance(surface, part.floor, 2.0, nullptr, nullptr, 0, &part.walls), {});
  const double top = 6 + std::sqrt(clear * clear - 1.7 * 1.7);
  EXPECT_NEAR(top, 7.2512, 1e-3);
  EXPECT_EQ(res.report["pushed_off_left_out"], 0);
  for (std::size_t i = 0; i < res.path.passes[0].contact.size(); ++i) {
    const Eigen::Vector3d c = res.path.passes[0].contact[i] + 2.0 * res.path.passes[0].normal[i];
    EXPECT_GE(c.z(), top - 1e-9) << i;
    EXPECT_LE(c.z(), top + 0.001) << i;  // within a tenth of e of the lowest clear centre
    for (const auto& w : part.walls) EXPECT_GE((c - w).norm(), clear - 1e-9);
  }
  EXPECT_NEAR(res.report["highest_lift"].get<double>(), top - 2, 0.001);
}

TEST(GougeGuard, NodeSaysItsLiftsWithCtxWarn) {
  PointCloud pc;
  pc.points = plane_cloud();
  const NodeDecl& d = *builtin_registry().find("path.gouge_guard");
  nlohmann::json params;
  for (const auto& p : d.params) params[p.name] = p.default_value;
  std::vector<std::string> said;
  NodeContext ctx(d, "guard", "part", params,
                  {{"path", std::make_shared<const Toolpath>(plane_pass(0.5, 4, 0.1))},
                   {"cloud", std::make_shared<const PointCloud>(pc)}},
                  nullptr, [&](const std::string& m) { said.push_back(m); });
  d.run(ctx);
  auto report = std::dynamic_pointer_cast<const Report>(ctx.take_outputs().at("report"));
  ASSERT_TRUE(report);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0], report->data["warnings"][0].get<std::string>());
  // the lifted ball touches the plane 0.1 mm up the slope from where it was planned to
  EXPECT_EQ(said[0],
            "1 tool positions (0 of them added in the middle of moves) were lifted by up to 0.105 mm (most near "
            "x -2.981, y 1.024) where the planned ball would have cut up to 0.1 mm into the cloud's surface (raised "
            "by its uncertainty); the path leaves that much stock there");
}

TEST(GougeGuard, NodeReportsAndKeepsUV) {
  PointCloud pc;
  pc.points = plane_cloud();
  auto out = test::run_node(*builtin_registry().find("path.gouge_guard"), {},
                            {{"path", std::make_shared<const Toolpath>(plane_pass(0.5, 4, 0.1))},
                             {"cloud", std::make_shared<const PointCloud>(pc)}});
  auto path = std::dynamic_pointer_cast<const Toolpath>(out.at("toolpath"));
  auto report = std::dynamic_pointer_cast<const Report>(out.at("report"));
  ASSERT_TRUE(path && report);
  EXPECT_EQ(report->data["lifted_positions"], 1);
  EXPECT_EQ(path->passes[0].uv.size(), path->passes[0].contact.size());
}

TEST(GougeGuard, NodeTakesTheBandFromCloudSurfaceBand) {
  // Given the band (as the shipped graphs give it, cached apart from the tool), the same path as
  // with the band computed in the node; a band of another cloud is refused, saying so.
  PointCloud pc;
  pc.points = plane_cloud();
  pc.uncertainty.assign(pc.points.size(), 0.01);
  const auto cloud = std::make_shared<const PointCloud>(pc);
  const auto path = std::make_shared<const Toolpath>(plane_pass(0.5, 4, 0.1));
  auto band = test::run_node(*builtin_registry().find("cloud.surface_band"), {}, {{"cloud", cloud}}).at("band");
  const NodeDecl& guard = *builtin_registry().find("path.gouge_guard");
  auto alone = test::run_node(guard, {}, {{"path", path}, {"cloud", cloud}});
  auto given = test::run_node(guard, {}, {{"path", path}, {"cloud", cloud}, {"band", band}});
  const auto& a = std::dynamic_pointer_cast<const Toolpath>(alone.at("toolpath"))->passes[0].contact;
  const auto& b = std::dynamic_pointer_cast<const Toolpath>(given.at("toolpath"))->passes[0].contact;
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]) << i;
  EXPECT_EQ(std::dynamic_pointer_cast<const Report>(given.at("report"))->data["lifted_positions"], 21);

  PointCloud other = pc;
  other.points.pop_back();
  other.uncertainty.pop_back();
  auto other_band =
      test::run_node(*builtin_registry().find("cloud.surface_band"), {}, {{"cloud", std::make_shared<const PointCloud>(other)}})
          .at("band");
  try {
    test::run_node(guard, {}, {{"path", path}, {"cloud", cloud}, {"band", other_band}});
    FAIL();
  } catch (const NodeError& e) {
    EXPECT_STREQ(e.what(), "the band has 6560 places for a cloud of 6561 points: give cloud.surface_band of the same cloud");
  }
}

}  // namespace
}  // namespace scallop
