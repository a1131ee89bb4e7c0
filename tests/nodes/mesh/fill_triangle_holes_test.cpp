// Tests for fill_triangle_holes: QuadriFlow's three-edge holes closed, the mesh kept all quads.
#include "nodes/mesh/fill_triangle_holes.h"

#include <gtest/gtest.h>

#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/quad_remesh.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// The three quad sides of a triangular prism (bottom triangle 0 1 2 at z = 0, top 3 4 5 at z =
// 1), faces outward, its two triangular ends left open: two three-edge holes.
Mesh open_prism() {
  Mesh m;
  m.vertices = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0, 0, 1}, {2, 0, 1}, {0, 2, 1}};
  m.add_face({0, 1, 4, 3});
  m.add_face({1, 2, 5, 4});
  m.add_face({2, 0, 3, 5});
  return m;
}

double area(const Mesh& m) {
  double a = 0;
  for (double x : face_geometry(m).area) a += x;
  return a;
}

TEST(QuadRemeshHoles, TwoTriangleHolesAreClosedByAStripAndTheMeshStaysAllQuads) {
  Mesh m = open_prism();
  const auto loops = boundary_loops(m, mesh_edges(m));
  ASSERT_EQ(loops.size(), 2u);
  const TriangleHoleFill r = fill_triangle_holes(m, loops);
  EXPECT_EQ(r.holes, 2u);
  EXPECT_EQ(r.quads_split, 1u);
  EXPECT_EQ(r.left, 0u);
  // The two ends and one side cut in two: six quads on eight vertices, a cube's topology.
  ASSERT_EQ(m.num_faces(), 6u);
  for (std::size_t f = 0; f < 6; ++f) EXPECT_EQ(m.face_size(f), 4u);
  EXPECT_EQ(m.num_vertices(), 8u);
  const MeshTopology t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(orientable_manifold_problem(m), "");
  // The new vertices are the midpoints of one side's bottom and top edges; nothing moved, so the
  // area is the prism's: sides 2, 2 sqrt 2 and 2, ends 2 each.
  EXPECT_EQ(m.vertices[6].z(), m.vertices[7].z() == 0 ? 1 : 0);
  EXPECT_EQ((m.vertices[6] - m.vertices[7]).head<2>().norm(), 0);
  EXPECT_NEAR(area(m), 2 + std::sqrt(8.0) + 2 + 2 * 2, 1e-12);
}

TEST(QuadRemeshHoles, OnAMeshWithABorderAStripMayEndThere) {
  Mesh m = open_prism();
  const auto loops = boundary_loops(m, mesh_edges(m));
  // Only the bottom is a hole: its strip runs up a side to the top's border.
  std::vector<std::vector<std::uint32_t>> bottom;
  for (const auto& l : loops)
    if (m.vertices[l[0]].z() == 0) bottom.push_back(l);
  ASSERT_EQ(bottom.size(), 1u);
  const TriangleHoleFill r = fill_triangle_holes(m, bottom);
  EXPECT_EQ(r.holes, 1u);
  EXPECT_EQ(r.quads_split, 1u);
  ASSERT_EQ(m.num_faces(), 5u);
  for (std::size_t f = 0; f < 5; ++f) EXPECT_EQ(m.face_size(f), 4u);
  const auto after = boundary_loops(m, mesh_edges(m));
  ASSERT_EQ(after.size(), 1u);
  EXPECT_EQ(after[0].size(), 4u);  // the top, one edge split
  EXPECT_EQ(orientable_manifold_problem(m), "");
}

}  // namespace
}  // namespace scallop
