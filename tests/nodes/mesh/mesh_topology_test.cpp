#include "nodes/mesh/mesh_topology.h"

#include <gtest/gtest.h>

#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

using test::unit_cube;

TEST(MeshTopology, ACubeIsOneClosedComponentOfGenusZero) {
  Mesh m = unit_cube();
  auto e = mesh_edges(m);
  EXPECT_EQ(e.size(), 12u);
  for (std::size_t i = 0; i < e.size(); ++i) EXPECT_EQ(e.faces_on(i), 2u);
  auto t = mesh_topology(m, e);
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.degenerate_faces, 0u);
  // Newell's vector of the bottom face points down with length twice its area.
  EXPECT_TRUE(face_area_vector(m, 0).isApprox(Eigen::Vector3d(0, 0, -2)));
}

TEST(MeshTopology, AnOpenBoxHasOneBoundaryLoopAlongTheRemovedFace) {
  Mesh m = unit_cube();
  Mesh open;
  open.vertices = m.vertices;
  for (std::size_t f = 0; f < 6; ++f)
    if (f != 1) open.add_face_range(std::vector<std::uint32_t>(m.face(f), m.face(f) + 4));
  auto e = mesh_edges(open);
  auto loops = boundary_loops(open, e);
  ASSERT_EQ(loops.size(), 1u);
  std::vector<std::uint32_t> loop = loops[0];
  std::sort(loop.begin(), loop.end());
  EXPECT_EQ(loop, (std::vector<std::uint32_t>{4, 5, 6, 7}));
  auto t = mesh_topology(open, e);
  EXPECT_EQ(t.boundary_loops, 1);
  EXPECT_EQ(t.genus, 0);
}

TEST(MeshTopology, ThreeFacesOnAnEdgeAreNonManifoldTwoCubesTwoComponents) {
  Mesh m = unit_cube();
  m.vertices.push_back({0.5, 0.5, -1});
  m.add_face({0, 1, 8});  // a fin on the cube's edge 0-1
  auto t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_EQ(t.genus, -1);

  Mesh two = unit_cube();
  for (int i = 0; i < 8; ++i) two.vertices.push_back(two.vertices[i] + Eigen::Vector3d(3, 0, 0));
  for (std::size_t f = 0; f < 6; ++f) {
    std::vector<std::uint32_t> c(two.face(f), two.face(f) + 4);
    for (auto& v : c) v += 8;
    two.add_face_range(c);
  }
  two.vertices.push_back({9, 9, 9});  // on no face
  two.add_face({0, 1, 1});            // a repeated corner
  auto t2 = mesh_topology(two, mesh_edges(two));
  EXPECT_EQ(t2.components, 2);  // the degenerate face hangs on the first cube's edge 0-1
  EXPECT_EQ(t2.degenerate_faces, 1u);
  EXPECT_EQ(t2.isolated_vertices, 1u);
}

TEST(MeshTopology, VertexFacesListEachFaceAroundAVertexOnce) {
  Mesh m = unit_cube();
  m.vertices.push_back({9, 9, 9});  // on no face
  m.add_face({0, 1, 1});            // a repeated corner: listed once at vertex 1
  const VertexFaces vf = vertex_faces(m);
  ASSERT_EQ(vf.start.size(), m.num_vertices() + 1);
  EXPECT_EQ(std::vector<std::uint32_t>(vf.faces(0), vf.faces(0) + vf.count(0)), (std::vector<std::uint32_t>{0, 2, 4, 6}));
  EXPECT_EQ(std::vector<std::uint32_t>(vf.faces(1), vf.faces(1) + vf.count(1)), (std::vector<std::uint32_t>{0, 2, 5, 6}));
  EXPECT_EQ(std::vector<std::uint32_t>(vf.faces(7), vf.faces(7) + vf.count(7)), (std::vector<std::uint32_t>{1, 3, 5}));
  EXPECT_EQ(vf.count(8), 0u);
  EXPECT_EQ(vf.face.size(), 6u * 4 + 2);
}

}  // namespace
}  // namespace scallop
