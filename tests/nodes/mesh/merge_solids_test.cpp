// Tests for merge_overlapping_solids (mesh.repair's union of solids that cross).
#include "nodes/mesh/merge_solids.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "nodes/mesh/mesh_distance.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/repair.h"
#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

// The unit cube (six quads, outward) moved by `shift`, appended to m.
void add_cube(Mesh& m, const V& shift) {
  const Mesh cube = test::unit_cube();
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const V& v : cube.vertices) m.vertices.push_back(v + shift);
  for (std::size_t f = 0; f < cube.num_faces(); ++f) {
    auto c = test::corners(cube, f);
    for (auto& v : c) v += base;
    m.add_face_range(c);
  }
}

// The volume a closed, outward mesh bounds (divergence theorem over its faces' fans).
double volume(const Mesh& m) {
  double v = 0;
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < m.face_size(f); ++k)
      v += m.vertices[m.face(f)[0]].dot(m.vertices[m.face(f)[k]].cross(m.vertices[m.face(f)[k + 1]])) / 6;
  return v;
}

TEST(MergeSolids, TwoCubesThatOverlapBecomeTheirUnion) {
  // [0, 1]^3 and [0.5, 1.5]^3: one closed solid of volume 2 - 0.125. Inside both at
  // (0.75, 0.75, 0.75), the union's surface is nearest at its re-entrant edges (x = 1, y = 0.5 and
  // the like), sqrt(0.125) away. Before, the nearest faces were the cubes' own, 0.25 away and
  // inside the other cube, and the rays crossed both cubes: an even count, taken for outside.
  Mesh m;
  add_cube(m, V(0, 0, 0));
  add_cube(m, V(0.5, 0.5, 0.5));
  EXPECT_FALSE(MeshDistance(m).inside_by_rays(V(0.75, 0.75, 0.75)));
  const MergeSolidsReport r = merge_overlapping_solids(m);
  EXPECT_EQ(r.solids_merged, 1u);
  EXPECT_EQ(r.solids_not_merged, 0u);
  const MeshTopology t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_NEAR(volume(m), 1.875, 1e-12);
  const MeshDistance d(m);
  EXPECT_NEAR(d.signed_distance(V(0.75, 0.75, 0.75)), -std::sqrt(0.125), 1e-12);
  EXPECT_NEAR(d.signed_distance(V(0.25, 0.25, -0.5)), 0.5, 1e-12);
  EXPECT_NEAR(d.signed_distance(V(1.25, 1.25, 1.7)), 0.2, 1e-12);
}

TEST(MergeSolids, ASolidTurnedInwardIsTurnedOutBeforeTheUnion) {
  // The second cube faces inward, as orient_to_bound_a_volume may leave a solid it sees partly
  // inside another (it took it for a cavity): the union is still the two cubes' (before, the
  // ABC plate came out as its disc alone, inside out).
  Mesh m;
  add_cube(m, V(0, 0, 0));
  add_cube(m, V(0.5, 0.5, 0.5));
  for (std::size_t f = 6; f < 12; ++f)
    std::reverse(m.face_vertices.begin() + m.face_start[f], m.face_vertices.begin() + m.face_start[f + 1]);
  EXPECT_EQ(merge_overlapping_solids(m).solids_merged, 1u);
  EXPECT_NEAR(volume(m), 1.875, 1e-12);
}

TEST(MergeSolids, CubesApartOrOpenAreLeftAsTheyAre) {
  Mesh apart;
  add_cube(apart, V(0, 0, 0));
  add_cube(apart, V(2, 0, 0));
  const Mesh before = apart;
  const MergeSolidsReport r = merge_overlapping_solids(apart);
  EXPECT_EQ(r.solids_merged, 0u);
  EXPECT_EQ(apart.vertices, before.vertices);
  EXPECT_EQ(apart.face_vertices, before.face_vertices);  // quads kept
  // A cube with its top removed (open) through a closed one: not a solid, not merged.
  Mesh open;
  add_cube(open, V(0, 0, 0));
  add_cube(open, V(0.5, 0.5, 0.5));
  Mesh cut;
  cut.vertices = open.vertices;
  for (std::size_t f = 0; f < open.num_faces(); ++f)
    if (f != 1) cut.add_face_range(test::corners(open, f));
  EXPECT_EQ(merge_overlapping_solids(cut).solids_merged, 0u);
}

TEST(MergeSolids, RepairMergesThemAndSaysSo) {
  Mesh m;
  add_cube(m, V(0, 0, 0));
  add_cube(m, V(0.5, 0.5, 0.5));
  add_cube(m, V(3, 0, 0));  // apart: kept as its six quads
  RepairReport r;
  const Mesh out = repair_mesh(m, RepairOptions{}, r);
  EXPECT_EQ(r.solids_merged, 1u);
  EXPECT_EQ(mesh_topology(out, mesh_edges(out)).components, 2);
  EXPECT_NEAR(volume(out), 2.875, 1e-12);
  RepairOptions keep;
  keep.merge_overlapping = false;
  const Mesh apart = repair_mesh(m, keep, r);
  EXPECT_EQ(r.solids_merged, 0u);
  EXPECT_EQ(mesh_topology(apart, mesh_edges(apart)).components, 3);
}

}  // namespace
}  // namespace scallop
