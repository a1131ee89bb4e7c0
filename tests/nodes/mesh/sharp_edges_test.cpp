#include "nodes/mesh/sharp_edges.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

SharpEdges sharp(const Mesh& m, double angle = 50) { return sharp_edges(m, mesh_edges(m), angle); }

// A closed prism over a regular n-gon of radius 1 and height h: two caps fanned from their
// centres, n side quads cut into two triangles each; outward.
Mesh prism(int n, double h) {
  Mesh m;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * std::numbers::pi * k / n;
    m.vertices.push_back({std::cos(t), std::sin(t), 0});
    m.vertices.push_back({std::cos(t), std::sin(t), h});
  }
  const auto bottom = static_cast<std::uint32_t>(m.vertices.size());
  m.vertices.push_back({0, 0, 0});
  m.vertices.push_back({0, 0, h});
  for (std::uint32_t k = 0; k < static_cast<std::uint32_t>(n); ++k) {
    const std::uint32_t a = 2 * k, b = 2 * ((k + 1) % n);
    m.add_face({a, b, b + 1});
    m.add_face({a, b + 1, a + 1});
    m.add_face({bottom, b, a});
    m.add_face({bottom + 1, a + 1, b + 1});
  }
  return m;
}

TEST(SharpEdges, ACubeHasTwelveCurvesBetweenEightCorners) {
  const Mesh m = test::cube_mesh(4);
  const SharpEdges s = sharp(m);
  EXPECT_EQ(s.edges.size(), 48u);  // 12 edges of 4 segments
  EXPECT_DOUBLE_EQ(s.length, 12.0);
  ASSERT_EQ(s.corners.size(), 8u);
  for (auto c : s.corners) {
    const auto& p = m.vertices[c];
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(p[i] == 0 || p[i] == 1) << p.transpose();
  }
  ASSERT_EQ(s.curves.size(), 12u);
  for (const auto& c : s.curves) {
    EXPECT_FALSE(c.closed);
    ASSERT_EQ(c.vertices.size(), 5u);
    EXPECT_DOUBLE_EQ(c.length, 1.0);
    // From corner to corner along a straight line.
    EXPECT_TRUE(std::binary_search(s.corners.begin(), s.corners.end(), c.vertices.front()));
    EXPECT_TRUE(std::binary_search(s.corners.begin(), s.corners.end(), c.vertices.back()));
    const Eigen::Vector3d dir = m.vertices[c.vertices.back()] - m.vertices[c.vertices.front()];
    for (std::size_t k = 1; k < c.vertices.size(); ++k)
      EXPECT_NEAR((m.vertices[c.vertices[k]] - m.vertices[c.vertices[k - 1]]).normalized().dot(dir), 1.0, 1e-12);
  }
  EXPECT_TRUE(std::is_sorted(s.edges.begin(), s.edges.end()));
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.non_manifold_edges, 0u);
  // Every edge is 90 degrees or flat: any angle in (0, 90) finds the same.
  EXPECT_EQ(sharp(m, 1).edges, s.edges);
  EXPECT_EQ(sharp(m, 89.9).edges, s.edges);
  EXPECT_TRUE(sharp(m, 90).edges.empty());
}

TEST(SharpEdges, ASphereHasNone) {
  // Neighbouring faces of a 1280-face icosphere are about 10 degrees apart.
  const SharpEdges s = sharp(test::icosphere(3));
  EXPECT_TRUE(s.edges.empty());
  EXPECT_TRUE(s.curves.empty());
  EXPECT_TRUE(s.corners.empty());
  EXPECT_EQ(s.length, 0.0);
  EXPECT_FALSE(sharp(test::icosphere(3), 5).edges.empty());
}

TEST(SharpEdges, APrismsRimsAreTwoClosedCurvesWithoutCorners) {
  // Sides 30 degrees apart (n = 12): not sharp at 50; the rims at 90 are.
  const Mesh m = prism(12, 0.5);
  const SharpEdges s = sharp(m);
  EXPECT_EQ(s.edges.size(), 24u);
  EXPECT_TRUE(s.corners.empty());
  ASSERT_EQ(s.curves.size(), 2u);
  for (const auto& c : s.curves) {
    EXPECT_TRUE(c.closed);
    EXPECT_EQ(c.vertices.size(), 12u);
    EXPECT_NEAR(c.length, 12 * 2 * std::sin(std::numbers::pi / 12), 1e-12);
  }
  // At 20 degrees the 12 vertical edges join in: every rim vertex has three sharp edges.
  const SharpEdges t = sharp(m, 20);
  EXPECT_EQ(t.edges.size(), 36u);
  EXPECT_EQ(t.corners.size(), 24u);
  EXPECT_EQ(t.curves.size(), 36u);
}

TEST(SharpEdges, AnOpenCreaseEndsWhereItFadesAndBoundaryEdgesAreNotRated) {
  // Two flaps meeting along the x axis at 105.5 degrees (their normals 74.5 degrees apart): one
  // crease curve from end to end, no corner.
  Mesh m;
  for (int i = 0; i <= 3; ++i) {
    m.vertices.push_back({double(i), 0, 0});
    m.vertices.push_back({double(i), 1, 0});
    m.vertices.push_back({double(i), -std::cos(1.3), std::sin(1.3)});
  }
  for (std::uint32_t i = 0; i < 3; ++i) {
    const std::uint32_t a = 3 * i, b = 3 * (i + 1);
    m.add_face({a, b, b + 1});
    m.add_face({a, b + 1, a + 1});
    m.add_face({a, a + 2, b + 2});
    m.add_face({a, b + 2, b});
  }
  const SharpEdges s = sharp(m);
  ASSERT_EQ(s.curves.size(), 1u);
  EXPECT_EQ(s.curves[0].vertices, (std::vector<std::uint32_t>{0, 3, 6, 9}));
  EXPECT_FALSE(s.curves[0].closed);
  EXPECT_TRUE(s.corners.empty());
  EXPECT_EQ(s.boundary_edges, 10u);
  EXPECT_EQ(sharp(m, 74).edges.size(), 3u);
  EXPECT_TRUE(sharp(m, 75).edges.empty());
}

TEST(SharpEdges, EdgesWithThreeFacesAreCountedNotRated) {
  Mesh m = test::cube_mesh(2);
  const std::uint32_t b = m.face(0)[1], c = m.face(0)[2];
  m.vertices.push_back(Eigen::Vector3d(-1, -1, -1));
  m.add_face({b, c, static_cast<std::uint32_t>(m.vertices.size() - 1)});
  const SharpEdges s = sharp(m);
  EXPECT_EQ(s.non_manifold_edges, 1u);
  EXPECT_EQ(s.boundary_edges, 2u);  // the fin's two free edges
}

// A face turned over onto its neighbours (a vertex moved past its opposite edge): its three
// edges turn by 180 degrees. With a fold angle below that they are folds, not edges of the part;
// the cube's 90-degree edges stay sharp.
TEST(SharpEdges, AFaceTurnedOverIsAFoldNotAnEdge) {
  Mesh m = test::cube_mesh(4);
  // On the face z = 1 the vertex (0.5, 0.5, 1) moved past the far edge of one of its triangles.
  const auto centre = static_cast<std::uint32_t>(
      std::find(m.vertices.begin(), m.vertices.end(), Eigen::Vector3d(0.5, 0.5, 1)) - m.vertices.begin());
  ASSERT_LT(centre, m.vertices.size());
  const std::size_t before = sharp(m).edges.size();
  Mesh folded = m;
  folded.vertices[centre] = Eigen::Vector3d(0.5, 0.5, 1) + Eigen::Vector3d(0.3, 0.3, 0);
  const SharpEdges all = sharp(folded), parted = sharp_edges(folded, mesh_edges(folded), 50, 150);
  EXPECT_GT(all.edges.size(), before);  // the turned-over faces' edges read as sharp
  EXPECT_EQ(all.folds, 0u);
  EXPECT_EQ(parted.edges, sharp(m).edges);
  EXPECT_GT(parted.folds, 0u);
  EXPECT_EQ(parted.folds, all.edges.size() - before);
}

TEST(SharpEdges, RefusesAnAngleOutsideTheRange) {
  const Mesh m = test::cube_mesh(1);
  EXPECT_THROW(sharp(m, 180), std::invalid_argument);
  EXPECT_THROW(sharp(m, -1), std::invalid_argument);
  EXPECT_THROW(sharp(m, std::nan("")), std::invalid_argument);
  EXPECT_THROW(sharp_edges(m, mesh_edges(m), 50, 50), std::invalid_argument);
  EXPECT_THROW(sharp_edges(m, mesh_edges(m), 50, 181), std::invalid_argument);
}

}  // namespace
namespace mesh_nodes {
NodeDecl make_sharp_edges_node();
}  // namespace mesh_nodes
namespace {

TEST(SharpEdgesNode, SetsTheFeatureEdgesAndReportsTheCurves) {
  const NodeDecl d = mesh_nodes::make_sharp_edges_node();
  EXPECT_EQ(d.type, "mesh.sharp_edges");
  EXPECT_EQ(d.find_param("angle")->default_value, 50.0);
  Mesh in = test::cube_mesh(3);
  in.feature_edges = {{0, 1}};  // replaced
  auto out = test::run_node(d, {}, {{"mesh", std::make_shared<Mesh>(in)}});
  auto mesh = std::dynamic_pointer_cast<const Mesh>(out.at("mesh"));
  auto report = std::dynamic_pointer_cast<const Report>(out.at("report"));
  ASSERT_TRUE(mesh && report);
  const SharpEdges s = sharp(in);
  EXPECT_EQ(mesh->feature_edges, s.edges);
  EXPECT_EQ(mesh->vertices, in.vertices);
  EXPECT_EQ(mesh->face_vertices, in.face_vertices);
  const auto& j = report->data;
  EXPECT_EQ(j.at("angle_deg"), 50.0);
  EXPECT_EQ(j.at("sharp_edges"), 36);
  EXPECT_EQ(j.at("curves"), 12);
  EXPECT_EQ(j.at("closed_curves"), 0);
  EXPECT_EQ(j.at("corners"), 8);
  EXPECT_DOUBLE_EQ(j.at("length").get<double>(), 12.0);
  ASSERT_EQ(j.at("feature_curves").size(), 12u);
  EXPECT_EQ(j.at("feature_curves")[0].at("vertices").get<std::vector<std::uint32_t>>(), s.curves[0].vertices);
  EXPECT_EQ(j.at("feature_curves")[0].at("closed"), false);
  EXPECT_EQ(j.at("corner_vertices").get<std::vector<std::uint32_t>>(), s.corners);
}

}  // namespace
}  // namespace scallop
