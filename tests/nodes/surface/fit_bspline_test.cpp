// surface.fit_bspline: closed forms (a sampled bicubic and a plane reproduced, a sphere cap within
// the tolerance between the vertices too), shared borders on a segmented cylinder, the node.
#include "nodes/surface/fit_bspline.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "nodes/all_nodes.h"
#include "nodes/mesh/segment.h"
#include "nodes/surface/tessellate.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// rows by cols points (x_j, y_i, f(x_j, y_i)) on [0, lx] x [0, ly], row-major.
template <class F>
std::vector<Eigen::Vector3d> grid_of(std::uint32_t rows, std::uint32_t cols, double lx, double ly, F f) {
  std::vector<Eigen::Vector3d> p;
  for (std::uint32_t i = 0; i < rows; ++i)
    for (std::uint32_t j = 0; j < cols; ++j) {
      const double x = lx * j / (cols - 1), y = ly * i / (rows - 1);
      p.push_back({x, y, f(x, y)});
    }
  return p;
}

// A bicubic polynomial lies in the fit's spline space (x, y linear in u, v): the fit reproduces
// it everywhere, not only at the samples.
TEST(FitBSpline, ASampledBicubicIsReproducedTo1e9) {
  auto f = [](double x, double y) {
    return 0.3 + 0.02 * x - 0.05 * y + 0.004 * x * y - 0.001 * x * x * x + 0.0007 * y * y * y +
           0.00002 * x * x * x * y * y * y;
  };
  FitBSplineOptions o;
  o.tolerance = 1e-10;
  const GridFit fit = fit_grid_bspline(grid_of(7, 9, 16, 12, f), 7, 9, o);
  EXPECT_TRUE(fit.within_tolerance);
  EXPECT_EQ(fit.surface.degree_u, 3);
  EXPECT_EQ(fit.surface.poles_u, 9u);
  EXPECT_EQ(fit.surface.poles_v, 7u);
  for (double u = 0; u <= 1; u += 0.05)
    for (double v = 0; v <= 1; v += 0.05) {
      const Eigen::Vector3d p = surface_point(fit.surface, u, v);
      EXPECT_NEAR(p.x(), 16 * u, 1e-9);
      EXPECT_NEAR(p.y(), 12 * v, 1e-9);
      EXPECT_NEAR(p.z(), f(16 * u, 12 * v), 1e-9) << u << " " << v;
    }
}

// Smoothing does not bend a plane: the first, smoothest try meets any tolerance.
TEST(FitBSpline, APlaneIsFittedOnTheFirstTry) {
  FitBSplineOptions o;
  o.tolerance = 1e-12;
  const GridFit fit = fit_grid_bspline(grid_of(5, 6, 10, 8, [](double x, double y) { return 1 + 0.1 * x - 0.2 * y; }),
                                       5, 6, o);
  EXPECT_EQ(fit.smoothing, o.smoothing);
  EXPECT_LT(fit.max_error, 1e-12);
}

// A cap of a sphere of radius 50, vertices 2 mm apart: within the tolerance at the vertices, and
// (what the tolerance does not promise) between them too.
TEST(FitBSpline, ASphereCapFitsWithinTheToleranceBetweenItsVerticesToo) {
  const double R = 50;
  auto f = [&](double x, double y) { return std::sqrt(R * R - (x - 10) * (x - 10) - (y - 10) * (y - 10)); };
  FitBSplineOptions o;  // tolerance 0.00125 mm
  const GridFit fit = fit_grid_bspline(grid_of(11, 11, 20, 20, f), 11, 11, o);
  EXPECT_TRUE(fit.within_tolerance);
  EXPECT_LE(fit.max_error, o.tolerance);
  EXPECT_GT(fit.smoothing, 0) << "a sphere this gentle needs no interpolation";
  double worst = 0;
  for (double u = 0; u <= 1; u += 0.01)
    for (double v = 0; v <= 1; v += 0.01) {
      const Eigen::Vector3d p = surface_point(fit.surface, u, v);
      worst = std::max(worst, std::abs((p - Eigen::Vector3d(10, 10, 0)).norm() - R));
    }
  EXPECT_LE(worst, o.tolerance);
}

TEST(FitBSpline, ABorderCurveKeepsItsEndsAndTwoPointsAreALine) {
  FitBSplineOptions o;
  double err = -1;
  const std::vector<Eigen::Vector3d> pts{{0, 0, 0}, {1, 0.2, 0}, {2, 0.1, 0}, {3, -0.3, 0}, {4, 0, 1}};
  const auto poles = fit_border_curve(pts, o, &err);
  ASSERT_EQ(poles.size(), 5u);
  EXPECT_EQ(poles.front(), pts.front());
  EXPECT_EQ(poles.back(), pts.back());
  EXPECT_LE(err, o.tolerance);
  const std::vector<Eigen::Vector3d> two{{0, 0, 0}, {1, 2, 3}};
  EXPECT_EQ(fit_border_curve(two, o, &err), two);
  EXPECT_EQ(err, 0);
}

// The capped cylinder's six patches: caps and four sides meet along twelve whole borders, each
// one curve for both neighbours (gap exactly 0); the sides stay on the cylinder between vertices.
TEST(FitBSpline, NeighboursOnACylinderShareTheirBorderCurves) {
  SegmentOptions so;
  so.join = false;
  const Segments seg = segment_shf(test::capped_cylinder(8), so);
  ASSERT_EQ(seg.patches.size(), 6u);
  FitStats stats;
  const Surfaces s = fit_surfaces(seg, FitBSplineOptions{}, &stats);
  ASSERT_EQ(s.patches.size(), 6u);
  EXPECT_EQ(stats.shared_borders, 12u);
  EXPECT_EQ(stats.shared_edges, 12u * 8);
  EXPECT_EQ(stats.boundary_gap_max, 0.0);
  for (std::size_t p = 0; p < 6; ++p) {
    const SurfacePatch& sp = s.patches[p];
    EXPECT_LE(sp.fit_max_error, 0.00125) << p;
    EXPECT_EQ(sp.direction, seg.patches[p].direction);
    // S_u x S_v points along the machining direction, as the faces do.
    const SurfaceJet j = evaluate(sp.surface, 0.5, 0.5);
    EXPECT_GT(j.du.cross(j.dv).normalized().dot(sp.direction), 0.7) << p;
    if (std::abs(sp.direction.z()) > 0.5) {
      // A cap stays in its plane; its border curves round the outline's chords out to the circle
      // (0.074 mm off the chords, as the sides are; 0.32 with equally spaced knots).
      for (const auto& q : sp.surface.poles) EXPECT_NEAR(q.z(), sp.direction.z() > 0 ? 15 : 0, 1e-9);
      EXPECT_LT(sp.mesh_distance_max, 0.08);
      continue;
    }
    // The side's facets are chords of the circle, at most 14 degrees apart: sag up to
    // 10 (1 - cos 7 deg) = 0.075.
    EXPECT_GT(sp.mesh_distance_max, 0.01);
    EXPECT_LT(sp.mesh_distance_max, 0.08);
    double worst = 0;
    for (double u = 0; u <= 1; u += 0.02)
      for (double v = 0; v <= 1; v += 0.1) {
        const Eigen::Vector3d q = surface_point(sp.surface, u, v);
        worst = std::max(worst, std::abs(q.head<2>().norm() - 10));
      }
    // Eight vertices a quarter turn (0.2 rad apart): a cubic through them stays within 1e-3 R.
    EXPECT_LT(worst, 0.01) << p;
  }
  const Mesh m = tessellate_surfaces(s, 4);
  EXPECT_EQ(m.num_faces(), 6u * 16);
  EXPECT_EQ(m.feature_edges.size(), 6u * 16);
}

TEST(FitBSpline, ANonFiniteVertexIsNamed) {
  SegmentOptions so;
  Segments seg = segment_shf(test::capped_cylinder(4), so);
  seg.mesh.vertices[seg.patches[2].at(1, 1)].x() = NAN;
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { fit_surfaces(seg, FitBSplineOptions{}); }),
            "patch 2: vertex " + std::to_string(seg.patches[2].at(1, 1)) + " is not finite");
}

TEST(FitBSpline, NodeReportsEveryPatchAndRefusesNoPatches) {
  const NodeDecl& d = *builtin_registry().find("surface.fit_bspline");
  auto seg = std::make_shared<Segments>(segment_shf(test::capped_cylinder(4), SegmentOptions{}));
  auto out = test::run_node(d, {{"samples", 2}}, {{"segments", seg}});
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_EQ(r["patches"].size(), seg->patches.size());
  EXPECT_LE(r["fit_max_error"].get<double>(), 0.00125);
  EXPECT_EQ(r["patches_over_tolerance"], 0);
  EXPECT_EQ(r["boundary_gap_max"], 0.0);
  const auto& mesh = *std::dynamic_pointer_cast<const Mesh>(out.at("mesh"));
  EXPECT_EQ(mesh.num_faces(), seg->patches.size() * 4);

  // The value's cache form reads back the same.
  const auto& s = *std::dynamic_pointer_cast<const Surfaces>(out.at("surfaces"));
  std::stringstream bytes;
  s.serialize(bytes);
  const auto back = std::dynamic_pointer_cast<const Surfaces>(Surfaces::deserialize(bytes));
  ASSERT_EQ(back->patches.size(), s.patches.size());
  EXPECT_EQ(back->patches[1].surface.poles, s.patches[1].surface.poles);
  EXPECT_EQ(back->patches[1].surface.knots_v, s.patches[1].surface.knots_v);
  EXPECT_EQ(back->patches[1].fit_max_error, s.patches[1].fit_max_error);

  auto empty = std::make_shared<Segments>();
  EXPECT_EQ(test::error_of<NodeError>([&] { test::run_node(d, {}, {{"segments", empty}}); }),
            "the segments hold no patch: nothing to fit");
}

}  // namespace
}  // namespace scallop
