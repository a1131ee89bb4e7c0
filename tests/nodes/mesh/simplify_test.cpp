#include "nodes/mesh/simplify.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/sharp_edges.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace mesh_nodes {
NodeDecl make_simplify_node();
}  // namespace mesh_nodes

namespace {

double feature_length(const Mesh& m) {
  double length = 0;
  for (const auto& e : m.feature_edges) length += (m.vertices[e[1]] - m.vertices[e[0]]).norm();
  return length;
}

// Largest distance from a vertex to the cube [0, edge]^3's surface.
double off_cube(const Mesh& m, double edge) {
  double worst = 0;
  for (const auto& p : m.vertices) {
    double inside = 0, outside = 0;  // distance to the nearest side from within / beyond the cube
    inside = std::min({p.x(), p.y(), p.z(), edge - p.x(), edge - p.y(), edge - p.z()});
    outside = Eigen::Vector3d(std::max({0.0, -p.x(), p.x() - edge}), std::max({0.0, -p.y(), p.y() - edge}),
                              std::max({0.0, -p.z(), p.z() - edge}))
                  .norm();
    worst = std::max(worst, outside > 0 ? outside : std::abs(inside));
  }
  return worst;
}

Mesh with_sharp_edges(Mesh m) {
  m.feature_edges = sharp_edges(m, mesh_edges(m), 50).edges;
  return m;
}

TEST(Simplify, ACubeKeepsItsTwelveEdgesAndItsSides) {
  const Mesh cube = with_sharp_edges(test::cube_mesh(20, 10.0));  // 4800 triangles, 240 edges 0.5 long on features
  ASSERT_EQ(cube.num_faces(), 4800u);
  ASSERT_NEAR(feature_length(cube), 120.0, 1e-9);
  SimplifyReport r;
  const Mesh out = simplify_mesh(cube, {.target_faces = 1000}, r);
  EXPECT_LE(out.num_faces(), 1000u);
  EXPECT_EQ(r.faces_before, 4800u);
  EXPECT_EQ(r.faces_after, out.num_faces());
  EXPECT_EQ(r.feature_edges, 240u);
  EXPECT_EQ(out.feature_edges.size(), 240u);
  EXPECT_NEAR(feature_length(out), 120.0, 1e-9);  // every feature vertex stayed where it was
  EXPECT_LT(off_cube(out, 10.0), 1e-9);           // planes stay planes under plane quadrics
  EXPECT_LT(r.max_distance, 1e-9);
  const MeshTopology t = mesh_topology(out, mesh_edges(out));
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_TRUE(out.all_triangles());
}

TEST(Simplify, ASphereStaysNearItsSurface) {
  const Mesh sphere = test::icosphere(5, 10.0);  // 20480 triangles, edges about 0.6 long
  SimplifyReport r;
  const Mesh out = simplify_mesh(sphere, {.target_faces = 2000}, r);
  EXPECT_LE(out.num_faces(), 2000u);
  EXPECT_GT(out.num_faces(), 1900u);
  EXPECT_TRUE(out.feature_edges.empty());
  double worst = 0;
  for (const auto& p : out.vertices) worst = std::max(worst, std::abs(p.norm() - 10.0));
  // 2000 triangles on a sphere of radius 10: edges about 2.4 long, a facet's sag r (1 - cos(a/2r))
  // is about 0.07; its vertices stay closer than that.
  EXPECT_LT(worst, 0.07);
  EXPECT_LT(r.max_distance, 0.15);
  const MeshTopology t = mesh_topology(out, mesh_edges(out));
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
}

TEST(Simplify, AnOpenSheetKeepsItsBorder) {
  Mesh sheet = test::quad_sheet(30, 20, 0.5, [](double x, double y) { return 0.01 * x * y; });
  Mesh tri;  // each square cut into two triangles
  tri.vertices = sheet.vertices;
  for (std::size_t f = 0; f < sheet.num_faces(); ++f) {
    const auto* c = sheet.face(f);
    tri.add_face({c[0], c[1], c[2]});
    tri.add_face({c[0], c[2], c[3]});
  }
  SimplifyReport r;
  const Mesh out = simplify_mesh(tri, {.target_faces = 300}, r);
  EXPECT_EQ(r.border_edges, 100u);
  const MeshEdges edges = mesh_edges(out);
  const auto loops = boundary_loops(out, edges);
  ASSERT_EQ(loops.size(), 1u);
  EXPECT_EQ(loops[0].size(), 100u);  // every border vertex kept
  EXPECT_LE(out.num_faces(), 300u);
}

// Collapsing a fine cube down to few faces: its edges' vertices never move, so without a cap the
// faces around them collapse into fans.
TEST(Simplify, NoVertexGetsMoreEdgesThanTheCap) {
  const Mesh cube = with_sharp_edges(test::cube_mesh(40, 10.0));  // 19 200 triangles, valence 6 at most
  SimplifyReport capped, uncapped;
  const Mesh out = simplify_mesh(cube, {.target_faces = 2000, .max_valence = 12}, capped);
  simplify_mesh(cube, {.target_faces = 2000, .max_valence = 1000000}, uncapped);
  EXPECT_GT(uncapped.max_valence, 12u);
  EXPECT_LE(capped.max_valence, 12u);
  std::vector<int> faces_at(out.num_vertices(), 0);  // on a closed triangle mesh, a vertex's edges
  for (std::size_t f = 0; f < out.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) ++faces_at[out.face(f)[k]];
  EXPECT_EQ(*std::max_element(faces_at.begin(), faces_at.end()), static_cast<int>(capped.max_valence));
  EXPECT_EQ(out.feature_edges.size(), 480u);      // every feature edge kept
  EXPECT_LT(off_cube(out, 10.0), 1e-9);
  const MeshTopology t = mesh_topology(out, mesh_edges(out));
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
}

TEST(Simplify, FewFacesPassUnchanged) {
  const Mesh cube = test::cube_mesh(2);
  SimplifyReport r;
  const Mesh out = simplify_mesh(cube, {.target_faces = 1000}, r);
  EXPECT_EQ(out.num_faces(), cube.num_faces());
  EXPECT_EQ(out.vertices, cube.vertices);
}

TEST(Simplify, RefusesQuadsAndNonManifoldMeshes) {
  SimplifyReport r;
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simplify_mesh(test::unit_cube(), {}, r); }),
            "face 0 has 4 corners: only triangle meshes are simplified");
  Mesh fin = test::tetrahedron();
  fin.vertices.push_back({1, 1, 1});
  fin.add_face({1, 2, 4});  // a third face on edge 1-2
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { simplify_mesh(fin, {}, r); }),
            "face 4 makes the mesh non-manifold or inconsistently oriented: run mesh.repair first");
}

TEST(Simplify, TheNodeReportsAndNamesItselfInErrors) {
  const Mesh cube = with_sharp_edges(test::cube_mesh(10, 10.0));
  auto out = test::run_node(mesh_nodes::make_simplify_node(), {{"target_faces", 400}},
                            {{"mesh", std::make_shared<Mesh>(cube)}});
  const auto& report = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_EQ(report["faces_before"], 1200);
  EXPECT_LE(report["faces_after"].get<int>(), 400);
  EXPECT_EQ(report["feature_edges"], 120);
  EXPECT_EQ(report["border_edges"], 0);
  EXPECT_LT(report["max_distance"].get<double>(), 1e-9);
  EXPECT_LE(report["max_valence"].get<int>(), 12);
  EXPECT_EQ(test::error_of<NodeError>([&] {
              test::run_node(mesh_nodes::make_simplify_node(), nlohmann::json::object(),
                             {{"mesh", std::make_shared<Mesh>(test::unit_cube())}});
            }),
            "mesh.simplify: face 0 has 4 corners: only triangle meshes are simplified");
}

}  // namespace
}  // namespace scallop
