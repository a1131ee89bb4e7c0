// subdivide_segments and surface.fit_bspline with the part: a coarse segmented cylinder (16 edges
// round) refined toward a fine one (256 edges round; its widest facet spans atan(1 / 32) at the
// middle of a side of the square it was bent from: sag 10 (1 - cos(atan(1 / 32) / 2)) = 0.0012
// mm): the new vertices on the part, the grids and faces consistent, the borders still shared,
// and the surfaces brought onto the part.
#include "nodes/surface/subdivide_segments.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "nodes/all_nodes.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/segment.h"
#include "nodes/mesh/sharp_edges.h"
#include "nodes/surface/fit_bspline.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

Segments coarse_cylinder() {
  SegmentOptions so;
  so.join = false;
  return segment_shf(test::capped_cylinder(4), so);
}

Mesh fine_cylinder() {
  Mesh part = test::capped_cylinder(64);
  part.feature_edges = sharp_edges(part, mesh_edges(part), 50).edges;
  return part;
}

TEST(SubdivideSegments, NewVerticesLieOnThePartAndEveryCellKeepsItsFace) {
  const Segments seg = coarse_cylinder();
  const Mesh part = fine_cylinder();
  SnapReport snap;
  const Segments fine = subdivide_segments(seg, part, &snap);
  ASSERT_EQ(fine.patches.size(), seg.patches.size());
  EXPECT_EQ(fine.mesh.num_faces(), 4 * seg.mesh.num_faces());
  EXPECT_EQ(fine.mesh.feature_edges.size(), 2 * seg.mesh.feature_edges.size());
  EXPECT_EQ(fine.clipping_edges.size(), 2 * seg.clipping_edges.size());
  EXPECT_EQ(fine.base_direction, seg.base_direction);
  EXPECT_EQ(snap.kept, 0u);
  const MeshDistance to_part(part);
  for (const auto& v : fine.mesh.vertices) EXPECT_LT(to_part(v), 1e-9);
  for (const auto& v : fine.mesh.vertices)
    if (v.z() > 1e-9 && v.z() < 15 - 1e-9) {
      EXPECT_LE(v.head<2>().norm(), 10 + 1e-9);
      EXPECT_GE(v.head<2>().norm(), 10 * std::cos(std::atan(1.0 / 32) / 2) - 1e-9);
    }
  for (std::size_t p = 0; p < seg.patches.size(); ++p) {
    const SegmentPatch &a = seg.patches[p], &b = fine.patches[p];
    ASSERT_EQ(b.rows, 2 * a.rows - 1);
    ASSERT_EQ(b.cols, 2 * a.cols - 1);
    EXPECT_EQ(b.direction, a.direction);
    for (std::uint32_t i = 0; i < a.rows; ++i)
      for (std::uint32_t j = 0; j < a.cols; ++j) EXPECT_EQ(b.at(2 * i, 2 * j), a.at(i, j));
    for (std::uint32_t i = 0; i + 1 < b.rows; ++i)
      for (std::uint32_t j = 0; j + 1 < b.cols; ++j) {
        const std::uint32_t f = b.faces[std::size_t(i) * (b.cols - 1) + j];
        const std::set<std::uint32_t> corners(fine.mesh.face(f), fine.mesh.face(f) + fine.mesh.face_size(f));
        EXPECT_EQ(corners, (std::set<std::uint32_t>{b.at(i, j), b.at(i, j + 1), b.at(i + 1, j), b.at(i + 1, j + 1)}))
            << p << " " << i << " " << j;
      }
  }
}

TEST(SubdivideSegments, TheFitGoesOntoThePartAndTheBordersStayShared) {
  const Segments seg = coarse_cylinder();
  const Mesh part = fine_cylinder();
  FitBSplineOptions o;
  o.part_tolerance = 1e-9;  // not met: both subdivisions are made
  FitStats stats;
  const Surfaces s = fit_surfaces(seg, o, &stats, {}, &part);
  EXPECT_EQ(stats.subdivisions, 2);
  EXPECT_EQ(stats.boundary_gap_max, 0.0);
  EXPECT_EQ(stats.shared_borders, 12u);
  ASSERT_EQ(s.patches.size(), seg.patches.size());
  ASSERT_EQ(stats.part_distance.size(), seg.patches.size());
  for (std::size_t p = 0; p < s.patches.size(); ++p) {
    EXPECT_EQ(s.patches[p].rows, 4 * (seg.patches[p].rows - 1) + 1);
    EXPECT_LE(stats.part_distance[p], stats.part_distance_after);
  }
  // Four vertices a quarter turn: the surfaces stood 0.066 mm off the part between them; through
  // sixteen, whose new ones lie on the part's facets (not on its circle), 0.0031: a few times
  // the part's own facets' sag (0.0012), twenty times closer.
  EXPECT_GT(stats.part_distance_before, 0.05);
  EXPECT_LT(stats.part_distance_after, 0.004);
  EXPECT_LT(stats.part_distance_after, stats.part_distance_before / 15);
  FitStats once;
  o.part_tolerance = stats.part_distance_before;  // met as it is: nothing to refine
  fit_surfaces(seg, o, &once, {}, &part);
  EXPECT_EQ(once.subdivisions, 0);
  EXPECT_EQ(once.part_distance_after, stats.part_distance_before);
}

TEST(SubdivideSegments, TheNodeReportsHowCloseThePatchesCameToThePart) {
  const NodeDecl& d = *builtin_registry().find("surface.fit_bspline");
  auto seg = std::make_shared<Segments>(coarse_cylinder());
  auto part = std::make_shared<Mesh>(fine_cylinder());
  auto out = test::run_node(d, {{"samples", 2}, {"part_tolerance", 0.01}}, {{"segments", seg}, {"part", part}});
  const auto& r = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_GE(r["subdivisions"].get<int>(), 1);
  EXPECT_GT(r["part_distance_before"].get<double>(), 0.02);
  EXPECT_LE(r["part_distance_max"].get<double>(), 0.01);
  EXPECT_LE(r["patches"][0]["part_distance_max"].get<double>(), 0.01);
  auto without = test::run_node(d, {{"samples", 2}}, {{"segments", seg}});
  EXPECT_FALSE(std::dynamic_pointer_cast<const Report>(without.at("report"))->data.contains("subdivisions"));
}

}  // namespace
}  // namespace scallop
