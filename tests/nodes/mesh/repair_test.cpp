// Tests for repair_mesh (CGAL's Polygon_mesh_processing) and the mesh.repair node.
#include "nodes/mesh/repair.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "engine/node.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace mesh_nodes {
NodeDecl make_repair_node();
}  // namespace mesh_nodes
using mesh_nodes::make_repair_node;
}  // namespace scallop

namespace scallop {
namespace {

using test::corners;
using test::unit_cube;
using V = Eigen::Vector3d;

// Faces f of `m` reversed.
Mesh reversed(Mesh m, std::initializer_list<std::size_t> faces) {
  for (std::size_t f : faces)
    std::reverse(m.face_vertices.begin() + m.face_start[f], m.face_vertices.begin() + m.face_start[f + 1]);
  return m;
}

Mesh repaired(const Mesh& soup, RepairReport& r, bool outward = true) {
  RepairOptions o;
  o.orient_outward = outward;
  return repair_mesh(soup, o, r);
}

// Every face's Newell normal points away from `centre` (through the face's centroid).
void expect_outward(const Mesh& m, const V& centre) {
  for (std::size_t f = 0; f < m.num_faces(); ++f) {
    V c = V::Zero();
    for (auto v : corners(m, f)) c += m.vertices[v];
    c /= static_cast<double>(m.face_size(f));
    EXPECT_GT(face_area_vector(m, f).dot(c - centre), 0) << "face " << f;
  }
}

void expect_closed_cube(const Mesh& m) {
  EXPECT_EQ(m.num_vertices(), 8u);
  ASSERT_EQ(m.num_faces(), 6u);
  for (std::size_t f = 0; f < 6; ++f) EXPECT_EQ(m.face_size(f), 4u);  // quads stay quads
  const MeshTopology t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(t.components, 1);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  expect_outward(m, V(0.5, 0.5, 0.5));
}

// The cube's six quads each with four vertices of its own (24 vertices), as an STL-like soup.
Mesh separate_faces(const Mesh& cube) {
  Mesh soup;
  for (std::size_t f = 0; f < cube.num_faces(); ++f) {
    std::vector<std::uint32_t> c;
    for (auto v : corners(cube, f)) {
      c.push_back(static_cast<std::uint32_t>(soup.vertices.size()));
      soup.vertices.push_back(cube.vertices[v]);
    }
    soup.add_face_range(c);
  }
  return soup;
}

// Appends a copy of `part` moved by `shift`.
void append(Mesh& m, const Mesh& part, const V& shift) {
  const auto base = static_cast<std::uint32_t>(m.vertices.size());
  for (const V& v : part.vertices) m.vertices.push_back(v + shift);
  for (std::size_t f = 0; f < part.num_faces(); ++f) {
    auto c = corners(part, f);
    for (auto& v : c) v += base;
    m.add_face_range(c);
  }
}

// The report's counts in its order: merged, simplified, pinched, degenerate, duplicate,
// isolated, reversed, edges cut, vertices split, stitched, turned outward.
std::vector<std::size_t> counts(const RepairReport& r) {
  return {r.points_merged,          r.faces_simplified,       r.pinched_faces_split,         r.degenerate_faces_removed,
          r.duplicate_faces_removed, r.isolated_vertices_removed, r.faces_reversed,           r.non_manifold_edges_cut,
          r.non_manifold_vertices_split, r.borders_stitched,  r.faces_turned_outward};
}
using Counts = std::vector<std::size_t>;

// A triangulated cube (4 x 4 squares a side, edge 4) with the 2 triangles of one corner square of
// its top taken out: a hole of 4 edges. fill_holes closes it, outward; a shorter limit leaves it.
TEST(Repair, FillHolesClosesTheHolesUpToItsLength) {
  const Mesh cube = test::cube_mesh(4, 4.0);
  Mesh holed;
  holed.vertices = cube.vertices;
  std::size_t removed = 0;
  for (std::size_t f = 0; f < cube.num_faces(); ++f) {
    V c = V::Zero();
    for (auto v : corners(cube, f)) c += cube.vertices[v];
    c /= double(cube.face_size(f));
    if (c.z() > 4 - 1e-9 && c.x() < 1 && c.y() < 1) {
      ++removed;
      continue;
    }
    holed.add_face_range(corners(cube, f));
  }
  ASSERT_GE(removed, 1u);
  RepairOptions o;
  o.fill_holes = 3;
  RepairReport r;
  const Mesh left = repair_mesh(holed, o, r);
  EXPECT_EQ(r.holes_filled, 0u);
  EXPECT_EQ(r.holes_left, 1u);
  EXPECT_EQ(mesh_topology(left, mesh_edges(left)).boundary_loops, 1);
  o.fill_holes = 4;
  const Mesh closed = repair_mesh(holed, o, r);
  EXPECT_EQ(r.holes_filled, 1u);
  EXPECT_EQ(r.holes_left, 0u);
  const MeshTopology t = mesh_topology(closed, mesh_edges(closed));
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  expect_outward(closed, V(2, 2, 2));
  double volume = 0;
  for (std::size_t f = 0; f < closed.num_faces(); ++f)
    volume += closed.vertices[closed.face(f)[0]].dot(face_area_vector(closed, f)) / 6.0;
  EXPECT_NEAR(volume, 64.0, 1e-9);  // the patch lies in the top's plane
}

// The largest corner angle of any face (degrees) and the shortest edge.
std::pair<double, double> largest_angle_and_shortest_edge(const Mesh& m) {
  double angle = 0, shortest = INFINITY;
  for (std::size_t f = 0; f < m.num_faces(); ++f)
    for (std::size_t c = 0; c < 3; ++c) {
      const V &a = m.vertices[m.face(f)[c]], &b = m.vertices[m.face(f)[(c + 1) % 3]], &o = m.vertices[m.face(f)[(c + 2) % 3]];
      shortest = std::min(shortest, (b - a).norm());
      angle = std::max(angle, std::acos(std::clamp((a - o).normalized().dot((b - o).normalized()), -1.0, 1.0)) * 180 / M_PI);
    }
  return {angle, shortest};
}

// Two slivers a random cloud's reconstruction makes, in a plane: a point 0.01 from another
// (needles: the edge between them goes) and a point 0.007 off the diagonal of a square (a cap,
// flipped). With slivers = 0 (the default) both stay.
TEST(Repair, SliversAreCollapsedOrFlippedWithinTheirSize) {
  Mesh needles;  // a hexagon fanned from two points 0.01 apart
  needles.vertices = {V(0, 0, 0), V(0.01, 0, 0)};
  for (int k = 0; k < 6; ++k) needles.vertices.emplace_back(std::cos(k * M_PI / 3), std::sin(k * M_PI / 3), 0);
  for (auto f : {std::array<std::uint32_t, 3>{1, 2, 3}, {1, 7, 2}, {1, 3, 0}, {0, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}, {0, 7, 1}})
    needles.add_face({f[0], f[1], f[2]});
  Mesh cap;  // a unit square, a point 0.007 below its diagonal
  cap.vertices = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0), V(0.5, 0.49, 0)};
  for (auto f : {std::array<std::uint32_t, 3>{0, 1, 4}, {1, 2, 4}, {0, 4, 2}, {0, 2, 3}}) cap.add_face({f[0], f[1], f[2]});
  for (const auto& [mesh, faces_after] : {std::pair{needles, 6u}, std::pair{cap, 4u}}) {
    RepairOptions o;
    RepairReport r;
    Mesh out = repair_mesh(mesh, o, r);
    EXPECT_EQ(out.num_faces(), mesh.num_faces());
    EXPECT_EQ(r.slivers_found, 0u);  // not looked for
    o.slivers = 0.05;
    out = repair_mesh(mesh, o, r);
    EXPECT_EQ(r.slivers_found, faces_after == 6u ? 2u : 1u);
    EXPECT_EQ(r.slivers_left, 0u);
    EXPECT_EQ(out.num_faces(), faces_after);
    const auto [angle, shortest] = largest_angle_and_shortest_edge(out);
    EXPECT_LT(angle, 160);
    EXPECT_GT(shortest, 0.5);
    for (const V& v : out.vertices) EXPECT_EQ(v.z(), 0);
    const MeshTopology t = mesh_topology(out, mesh_edges(out));
    EXPECT_EQ(t.components, 1);
    EXPECT_EQ(t.boundary_loops, 1);
  }
}

TEST(Repair, ACleanCubeIsLeftAsItIs) {
  RepairReport r;
  const Mesh m = repaired(unit_cube(), r);
  EXPECT_EQ(counts(r), Counts(11, 0));
  EXPECT_EQ(m.vertices, unit_cube().vertices);
  expect_closed_cube(m);
}

TEST(Repair, AFlippedFaceIsTurnedBackAndTheCubeFacesOutward) {
  RepairReport r;
  expect_closed_cube(repaired(reversed(unit_cube(), {3}), r));
  EXPECT_EQ(counts(r), (Counts{0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0}));
  // the first face flipped: the other five are turned to agree with it, then all six outward
  expect_closed_cube(repaired(reversed(unit_cube(), {0}), r));
  EXPECT_EQ(counts(r), (Counts{0, 0, 0, 0, 0, 0, 5, 0, 0, 0, 6}));
  // a cube facing inward throughout is consistent already: only turned outward
  const Mesh inward = reversed(unit_cube(), {0, 1, 2, 3, 4, 5});
  expect_closed_cube(repaired(inward, r));
  EXPECT_EQ(counts(r), (Counts{0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 6}));
  // ... unless asked not to
  const Mesh kept = repaired(inward, r, false);
  for (std::size_t f = 0; f < 6; ++f) EXPECT_EQ(corners(kept, f), corners(inward, f));
  EXPECT_EQ(r.faces_turned_outward, 0u);
}

TEST(Repair, ACubeOfSeparateFacesIsJoinedIntoOneClosedMesh) {
  RepairReport r;
  const Mesh soup = reversed(separate_faces(unit_cube()), {2});
  ASSERT_EQ(soup.num_vertices(), 24u);
  EXPECT_EQ(mesh_topology(soup, mesh_edges(soup)).components, 6);
  // the coincident corners are merged (so no border is left for stitch_borders), the flipped
  // face turned back
  expect_closed_cube(repaired(soup, r));
  EXPECT_EQ(counts(r), (Counts{16, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0}));
}

TEST(Repair, ABowTieVertexIsSplit) {
  Mesh bow;
  bow.vertices = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(-1, 0, 0), V(-1, -1, 0)};
  bow.add_face({0, 1, 2});
  bow.add_face({0, 3, 4});
  RepairReport r;
  const Mesh m = repaired(bow, r);
  EXPECT_EQ(counts(r), (Counts{0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0}));
  ASSERT_EQ(m.num_vertices(), 6u);
  ASSERT_EQ(m.num_faces(), 2u);
  // the two triangles share no vertex now, but both still have one at the origin
  auto a = corners(m, 0), b = corners(m, 1);
  for (auto v : a) EXPECT_EQ(std::count(b.begin(), b.end(), v), 0);
  int at_origin = 0;
  for (const V& v : m.vertices) at_origin += v.isZero();
  EXPECT_EQ(at_origin, 2);
  EXPECT_EQ(mesh_topology(m, mesh_edges(m)).components, 2);
}

TEST(Repair, NonManifoldEdgesAreCutApart) {
  // a fin on the cube's edge 0-1: three faces on one edge
  Mesh fin = unit_cube();
  fin.vertices.push_back({0.5, 0.5, -1});
  fin.add_face({0, 1, 8});
  RepairReport r;
  Mesh m = repaired(fin, r);
  EXPECT_EQ(counts(r), (Counts{0, 0, 0, 0, 0, 0, 0, 1, 2, 0, 0}));
  MeshTopology t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(m.num_vertices(), 11u);  // the fin's edge has its own two ends now
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.boundary_loops, 1);  // the fin's; the cube stays closed
  // two cubes on one edge (four faces on it) become two closed cubes
  Mesh two = unit_cube();
  append(two, unit_cube(), V(1, 1, 0));
  m = repaired(two, r);
  EXPECT_EQ(counts(r), (Counts{2, 0, 0, 0, 0, 0, 0, 1, 2, 0, 0}));
  t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(m.num_vertices(), 16u);
  EXPECT_EQ(t.components, 2);
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.genus, 0);
}

TEST(Repair, DegenerateAndDuplicateFacesAreDropped) {
  Mesh soup = test::tetrahedron();
  soup.add_face({0, 1, 1});                    // a repeated corner
  soup.vertices.push_back(soup.vertices[1]);   // vertex 4 at vertex 1's place ...
  soup.add_face({0, 1, 4});                    // ... so this face is degenerate once they merge
  soup.add_face({1, 2, 0});                    // face 0 again, the other way round
  RepairReport r;
  const Mesh m = repaired(soup, r);
  EXPECT_EQ(counts(r), (Counts{1, 2, 0, 2, 1, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(m.num_vertices(), 4u);
  EXPECT_EQ(m.num_faces(), 4u);
  const MeshTopology t = mesh_topology(m, mesh_edges(m));
  EXPECT_EQ(t.boundary_loops, 0);
  EXPECT_EQ(t.degenerate_faces, 0u);
  expect_outward(m, V(0.25, 0.25, 0.25));
}

TEST(Repair, Errors) {
  RepairReport r;
  Mesh m;
  m.vertices = {V(0, 0, 0)};
  try {
    repaired(m, r);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "the mesh has no faces");
  }
  m.vertices.push_back(V(1, 0, 0));
  m.add_face({0, 1, 1});
  try {
    repaired(m, r);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "no face is left: every one was degenerate");
  }
  m.add_face({0, 1, 5});
  try {
    repaired(m, r);
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "a face has corner 5 but there are 2 vertices");
  }
}

TEST(Repair, NodeReportsTheChangesAndTheTopologyBeforeAndAfter) {
  const NodeDecl d = make_repair_node();
  EXPECT_EQ(d.type, "mesh.repair");
  EXPECT_EQ(d.find_input("mesh")->type, "Mesh");
  EXPECT_EQ(d.find_output("mesh")->type, "Mesh");
  EXPECT_EQ(d.find_output("report")->type, "Report");
  EXPECT_EQ(d.find_param("orient_outward")->default_value, true);

  Mesh soup = reversed(separate_faces(unit_cube()), {2});
  soup.face_label.assign(6, 1);  // dropped: the faces are renumbered
  auto out = test::run_node(d, {}, {{"mesh", std::make_shared<Mesh>(soup)}});
  auto mesh = std::dynamic_pointer_cast<const Mesh>(out.at("mesh"));
  ASSERT_TRUE(mesh);
  expect_closed_cube(*mesh);
  EXPECT_FALSE(mesh->has_labels());
  const auto& report = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_EQ(report["changes"], (nlohmann::json{{"points_merged", 16},
                                               {"faces_simplified", 0},
                                               {"pinched_faces_split", 0},
                                               {"degenerate_faces_removed", 0},
                                               {"duplicate_faces_removed", 0},
                                               {"isolated_vertices_removed", 0},
                                               {"faces_reversed", 1},
                                               {"non_manifold_edges_cut", 0},
                                               {"non_manifold_vertices_split", 0},
                                               {"borders_stitched", 0},
                                               {"holes_filled", 0},
                                               {"holes_left", 0},
                                               {"slivers_found", 0},
                                               {"slivers_left", 0},
                                               {"faces_turned_outward", 0},
                                               {"solids_merged", 0},
                                               {"solids_not_merged", 0}}));
  EXPECT_EQ(report["before"]["vertices"], 24);
  EXPECT_EQ(report["before"]["components"], 6);
  EXPECT_EQ(report["before"]["boundary_loops"], 6);
  EXPECT_EQ(report["after"]["vertices"], 8);
  EXPECT_EQ(report["after"]["quads"], 6);
  EXPECT_EQ(report["after"]["components"], 1);
  EXPECT_EQ(report["after"]["closed"], true);
  EXPECT_EQ(report["after"]["genus"], 0);

  try {
    test::run_node(d, {}, {{"mesh", std::make_shared<Mesh>()}});
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), "the mesh has no faces");
  }
}

}  // namespace
}  // namespace scallop
