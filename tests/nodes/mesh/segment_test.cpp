#include "nodes/mesh/segment.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "nodes/all_nodes.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

Segments segment(const Mesh& m, SegmentStats* stats = nullptr, double min_dot = 0.05) {
  SegmentOptions o;
  o.min_normal_dot = min_dot;
  return segment_shf(m, o, stats);
}

// What every segmentation must hold: each face in exactly one patch, labels matching; each patch
// a grid whose cells are its faces with their corners; corners counter-clockwise seen along the
// direction; every face normal n with n . d >= min_normal_dot, as reported.
void expect_valid(const Segments& s) {
  const Mesh& m = s.mesh;
  const FaceGeometry g = face_geometry(m);
  std::vector<int> seen(m.num_faces(), 0);
  for (std::size_t i = 0; i < s.patches.size(); ++i) {
    const SegmentPatch& p = s.patches[i];
    ASSERT_GE(p.rows, 2u);
    ASSERT_GE(p.cols, 2u);
    ASSERT_EQ(p.grid.size(), std::size_t(p.rows) * p.cols);
    ASSERT_EQ(p.faces.size(), std::size_t(p.rows - 1) * (p.cols - 1));
    EXPECT_NEAR(p.direction.norm(), 1.0, 1e-12);
    double worst = 2;
    for (auto f : p.faces) {
      ++seen[f];
      EXPECT_EQ(m.face_label[f], static_cast<int>(i));
      worst = std::min(worst, g.normal[f].dot(p.direction));
    }
    EXPECT_NEAR(worst, p.min_normal_dot, 1e-12);
    // Cell (i, j) is the face on the grid's vertices (i, j), (i, j+1), (i+1, j+1), (i+1, j).
    for (std::uint32_t r = 0; r + 1 < p.rows; ++r)
      for (std::uint32_t c = 0; c + 1 < p.cols; ++c) {
        const auto f = p.faces[r * (p.cols - 1) + c];
        std::set<std::uint32_t> want{p.at(r, c), p.at(r, c + 1), p.at(r + 1, c + 1), p.at(r + 1, c)};
        std::set<std::uint32_t> got(m.face(f), m.face(f) + 4);
        EXPECT_EQ(want, got) << "patch " << i << " cell " << r << "," << c;
      }
    const Eigen::Vector3d du = m.vertices[p.at(0, 1)] - m.vertices[p.at(0, 0)];
    const Eigen::Vector3d dv = m.vertices[p.at(1, 0)] - m.vertices[p.at(0, 0)];
    EXPECT_GT(du.cross(dv).dot(p.direction), 0) << "patch " << i << " is not counter-clockwise";
  }
  for (std::size_t f = 0; f < m.num_faces(); ++f) EXPECT_EQ(seen[f], 1) << "face " << f;
  // The sharp features are on the patches' borders (the SHF's condition 3).
  const MeshEdges edges = mesh_edges(m);
  for (const auto& [a, b] : m.feature_edges) {
    const auto e = *edges.find(a, b);
    if (edges.faces_on(e) == 2)
      EXPECT_NE(m.face_label[edges.faces(e)[0]], m.face_label[edges.faces(e)[1]]) << "sharp edge " << a << "-" << b;
  }
}

// The box's faces removed where keep(label) is false, vertices kept.
Mesh without_sides(const Mesh& m, std::set<int> drop) {
  Mesh out;
  out.vertices = m.vertices;
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    if (!drop.count(m.face_label[f])) {
      out.add_face({m.face(f)[0], m.face(f)[1], m.face(f)[2], m.face(f)[3]});
      out.face_label.push_back(m.face_label[f]);
    }
  return out;
}

// The patch's side of the box (all its faces from one side).
int side_of(const Mesh& box, const SegmentPatch& p) {
  const int s = box.face_label[p.faces[0]];
  for (auto f : p.faces)
    if (box.face_label[f] != s) return -1;
  return s;
}

TEST(Segment, ABoxGivesItsSixSidesTheirDirectionsTheSideNormals) {
  const Mesh box = test::quad_box({8, 6, 4}, {40, 30, 20});
  SegmentStats stats;
  const Segments s = segment(box, &stats);
  expect_valid(s);
  EXPECT_EQ(stats.extraordinary_points, 8u);  // the corners, valence 3
  EXPECT_EQ(stats.connection_lines, 12u);     // the box's edges, EP to EP
  EXPECT_EQ(stats.sharp_edges, 4u * (8 + 6 + 4));
  ASSERT_EQ(s.patches.size(), 6u);
  std::set<int> sides;
  for (const auto& p : s.patches) {
    const int side = side_of(box, p);
    ASSERT_GE(side, 0);
    sides.insert(side);
    EXPECT_NEAR((p.direction - test::cube_side_normal(side)).norm(), 0, 1e-9);
    EXPECT_NEAR(p.min_normal_dot, 1.0, 1e-12);
  }
  EXPECT_EQ(sides.size(), 6u);
  EXPECT_EQ(s.clipping_edges.size(), 4u * (8 + 6 + 4));  // exactly the box's edges
}

TEST(Segment, ABoxWithoutItsBaseGivesTheFiveOtherSides) {
  const Mesh box = without_sides(test::quad_box({8, 6, 4}, {40, 30, 20}), {2});
  const Segments s = segment(box);
  expect_valid(s);
  ASSERT_EQ(s.patches.size(), 5u);
  for (const auto& p : s.patches) {
    const int side = side_of(box, p);
    ASSERT_GE(side, 0);
    EXPECT_NE(side, 2);
    EXPECT_NEAR((p.direction - test::cube_side_normal(side)).norm(), 0, 1e-9);
  }
}

TEST(Segment, ACylinderWithCapsGivesTheCapsAndFourSideHeightFields) {
  const Mesh m = test::capped_cylinder(8);
  const Segments s = segment(m);
  expect_valid(s);
  ASSERT_EQ(s.patches.size(), 6u);
  int caps = 0, sides = 0;
  for (const auto& p : s.patches) {
    if (std::abs(p.direction.z()) > 1 - 1e-9) {
      ++caps;
      EXPECT_NEAR(p.min_normal_dot, 1.0, 1e-9);
      EXPECT_EQ(p.faces.size(), 64u);
    } else {
      ++sides;
      EXPECT_NEAR(p.direction.z(), 0, 1e-9);
      // A quarter of the side: normals within 45 degrees of its middle, less half a facet.
      EXPECT_GT(p.min_normal_dot, 0.7);
      EXPECT_EQ(p.faces.size(), 64u);
    }
  }
  EXPECT_EQ(caps, 2);
  EXPECT_EQ(sides, 4);
}

TEST(Segment, NeighboursJoinWhileTheUnionStaysAHeightFieldAboveTheLimit) {
  const Mesh m = test::capped_cylinder(8);
  SegmentOptions o;
  o.join_min_normal_dot = 0.06;  // a half side's end facets are about 86 degrees from its middle
  SegmentStats stats;
  const Segments s = segment_shf(m, o, &stats);
  expect_valid(s);
  EXPECT_EQ(stats.joins, 2u);  // four quarters into two halves; three quarters see no direction
  ASSERT_EQ(s.patches.size(), 4u);
  for (const auto& p : s.patches) {
    EXPECT_GT(p.min_normal_dot, 0.06);
    if (std::abs(p.direction.z()) < 1e-9) {
      EXPECT_EQ(p.faces.size(), 128u);
      EXPECT_LT(p.min_normal_dot, 0.15);  // the end facets of a half turn face nearly sideways
    }
  }
  o.join = false;
  EXPECT_EQ(segment_shf(m, o).patches.size(), 6u);
}

TEST(Segment, NoJoinWhereTheUnionsBorderWouldTurnAtACorner) {
  // A box whose edges are not sharp (theta 100 degrees): two neighbouring sides form a height
  // field (every n . d = cos 45 degrees, above join_min_normal_dot 0.5), but their union's border
  // would turn 90 degrees at the box's corners, where the B-spline fitted to it folds over.
  const Mesh box = test::quad_box({4, 4, 4}, {20, 20, 20});
  SegmentOptions o;
  o.sharp_angle_deg = 100;
  SegmentStats stats;
  const Segments s = segment_shf(box, o, &stats);
  expect_valid(s);
  EXPECT_EQ(stats.sharp_edges, 0u);
  EXPECT_EQ(stats.joins, 0u);
  ASSERT_EQ(s.patches.size(), 6u);
  for (const auto& p : s.patches) EXPECT_GE(side_of(box, p), 0);
}

TEST(Segment, ASphereWithoutSharpEdgesIsCutByItsExtraordinaryPoints) {
  Mesh m = test::quad_box({6, 6, 6}, {2, 2, 2});
  for (auto& v : m.vertices) v = (v - Eigen::Vector3d(1, 1, 1)).normalized() * 20;
  SegmentStats stats;
  const Segments s = segment(m, &stats);
  expect_valid(s);
  EXPECT_EQ(stats.sharp_edges, 0u);
  EXPECT_EQ(stats.extraordinary_points, 8u);
  ASSERT_EQ(s.patches.size(), 6u);
  for (const auto& p : s.patches) EXPECT_GT(p.min_normal_dot, 0.5);
}

TEST(Segment, AnOpenHeightFieldIsOnePatch) {
  const Mesh m = test::quad_sheet(12, 9, 2.0, [](double x, double y) { return 3 * std::sin(x / 8) * std::cos(y / 9); });
  const Segments s = segment(m);
  expect_valid(s);
  ASSERT_EQ(s.patches.size(), 1u);
  EXPECT_EQ(s.patches[0].rows, 10u);
  EXPECT_EQ(s.patches[0].cols, 13u);
  EXPECT_GT(s.patches[0].direction.z(), 0.9);
}

TEST(Segment, AnLShapeIsCutFromItsConcaveCornerIntoTwoRectangles) {
  const Mesh sheet = test::quad_sheet(6, 6, 1.0, [](double, double) { return 0.0; });
  Mesh m;
  m.vertices = sheet.vertices;
  for (std::size_t f = 0; f < sheet.num_faces(); ++f)
    if (!(f % 6 >= 3 && f / 6 >= 3)) m.add_face({sheet.face(f)[0], sheet.face(f)[1], sheet.face(f)[2], sheet.face(f)[3]});
  SegmentStats stats;
  const Segments s = segment(m, &stats);
  expect_valid(s);
  ASSERT_EQ(s.patches.size(), 2u);
  EXPECT_EQ(s.patches[0].faces.size() + s.patches[1].faces.size(), 27u);
  EXPECT_EQ(stats.clipping_by_priority[6], 3u);  // one grid line of three edges from the corner
}

TEST(Segment, ASurfaceThatIsNoHeightFieldIsHalvedUntilEveryPartIs) {
  // 270 degrees of a cylinder of radius 10: no direction sees all of it.
  Mesh m = test::quad_sheet(24, 4, 1.0, [](double, double) { return 0.0; });
  for (auto& v : m.vertices) {
    const double t = v.x() / 24 * 1.5 * std::numbers::pi;
    v = Eigen::Vector3d(10 * std::cos(t), v.y(), 10 * std::sin(t));
  }
  // The sheet's faces are counter-clockwise seen from +z at t = 0, i.e. from -y ... orient them
  // outward (away from the axis) by their first face.
  const FaceGeometry g0 = face_geometry(m);
  if (g0.normal[0].dot(face_geometry(m).centroid[0] - Eigen::Vector3d(0, face_geometry(m).centroid[0].y(), 0)) < 0)
    for (std::size_t f = 0; f < m.num_faces(); ++f) std::reverse(m.face_vertices.begin() + m.face_start[f],
                                                                 m.face_vertices.begin() + m.face_start[f + 1]);
  SegmentStats stats;
  const Segments s = segment(m, &stats, 0.2);
  expect_valid(s);
  EXPECT_GE(s.patches.size(), 2u);
  EXPECT_GE(stats.height_field_splits, 1u);
  for (const auto& p : s.patches) EXPECT_GT(p.min_normal_dot, 0.2);
}

TEST(Segment, ATriangleMeshIsRefusedNamingTheFace) {
  const Mesh m = test::tetrahedron();
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { segment(m); }),
            "face 0 has 3 corners; the segmentation cuts a quad mesh (mesh.quad_remesh makes one)");
}

TEST(Segment, TheBestDirectionIsTheAxisOfTheSmallestCapOfNormals) {
  // Normals on a cone of half-angle 30 degrees about a tilted axis, plus some inside it.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Vector3d a = axis.unitOrthogonal(), b = axis.cross(a);
  std::vector<Eigen::Vector3d> n;
  const double h = 30 * std::numbers::pi / 180;
  for (int k = 0; k < 7; ++k) {
    const double t = 2 * std::numbers::pi * k / 7;
    n.push_back(std::cos(h) * axis + std::sin(h) * (std::cos(t) * a + std::sin(t) * b));
  }
  n.push_back(axis);
  n.push_back((axis + 0.1 * a).normalized());
  const auto [d, worst] = best_height_field_direction(n);
  EXPECT_NEAR((d - axis).norm(), 0, 1e-3);
  EXPECT_NEAR(worst, std::cos(h), 1e-3);  // Badoiu-Clarkson: near the optimum, not at it
  EXPECT_LE(worst, std::cos(h) + 1e-12);
}

TEST(Segment, TheNodeReportsPatchesAndKeepsTheBaseDirection) {
  const Registry& reg = builtin_registry();
  auto box = std::make_shared<Mesh>(without_sides(test::quad_box({4, 4, 4}, {10, 10, 10}), {2}));
  auto base = std::make_shared<Report>();
  base->data = {{"base_direction", {0, 0, -1}}};
  auto out = test::run_node(*reg.find("mesh.segment"), {}, {{"mesh", box}, {"base", base}});
  const auto& report = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  ASSERT_EQ(report["patches"].size(), 5u);
  EXPECT_DOUBLE_EQ(report["patches"][0]["area"].get<double>(), 100.0);
  const auto s = std::dynamic_pointer_cast<const Segments>(out.at("segments"));
  EXPECT_EQ(s->base_direction, Eigen::Vector3d(0, 0, -1));
  EXPECT_EQ(test::error_of<NodeError>([&] {
              test::run_node(*reg.find("mesh.segment"), {}, {{"mesh", std::make_shared<Mesh>(test::tetrahedron())}});
            }),
            "mesh.segment: face 0 has 3 corners; the segmentation cuts a quad mesh (mesh.quad_remesh makes one)");
}

}  // namespace
}  // namespace scallop
