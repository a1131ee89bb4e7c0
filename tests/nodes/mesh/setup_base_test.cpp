// Tests for the K-means of normals (kmeans), setup_base and the mesh.setup_base node.
#include "nodes/mesh/setup_base.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "engine/node.h"
#include "nodes/geom/kmeans.h"
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/keep_faces.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace mesh_nodes {
NodeDecl make_setup_base_node();
}  // namespace mesh_nodes
using mesh_nodes::make_setup_base_node;
}  // namespace scallop

namespace scallop {
namespace {

using V = Eigen::Vector3d;

struct Outcome {
  Mesh mesh;
  nlohmann::json report;
};

Outcome run(const Mesh& m, const nlohmann::json& params = nlohmann::json::object()) {
  auto out = test::run_node(make_setup_base_node(), params, {{"mesh", std::make_shared<Mesh>(m)}});
  return {*std::dynamic_pointer_cast<const Mesh>(out.at("mesh")),
          std::dynamic_pointer_cast<const Report>(out.at("report"))->data};
}

std::string refusal(const Mesh& m, const nlohmann::json& params = nlohmann::json::object()) {
  return test::error_of<NodeError>([&] { run(m, params); });
}

V direction(const nlohmann::json& report) {
  return V(report["base_direction"][0], report["base_direction"][1], report["base_direction"][2]);
}

TEST(SetupBase, KMeansFindsTwoClustersOfNormals) {
  // Unit normals tilted up to 8 degrees about +z (12 of them) and about +x (7), weighted.
  std::vector<V> normals;
  std::vector<double> weights;
  for (int i = 0; i < 19; ++i) {
    const double tilt = (i % 4 + 1) * 2.0 * M_PI / 180, turn = i * 0.9;
    const V off(std::sin(tilt) * std::cos(turn), std::sin(tilt) * std::sin(turn), std::cos(tilt));
    normals.push_back(i < 12 ? off : V(off.z(), off.x(), off.y()));
    weights.push_back(1 + i % 3);
  }
  KMeansOptions o;
  o.k = 2;
  const KMeansResult r = kmeans(normals, weights, o);
  ASSERT_EQ(r.centre.size(), 2u);
  // The heavier cluster first: the 12 about +z.
  for (int i = 0; i < 19; ++i) EXPECT_EQ(r.label[i], i < 12 ? 0 : 1) << "normal " << i;
  for (int c = 0; c < 2; ++c) {
    V sum = V::Zero();
    double w = 0;
    for (int i = 0; i < 19; ++i)
      if (r.label[i] == c) sum += weights[i] * normals[i], w += weights[i];
    EXPECT_LT((r.centre[c] - sum / w).norm(), 1e-12);  // each centre the weighted mean of its cluster
    EXPECT_EQ(r.weight[c], w);
  }
  EXPECT_EQ(r.size, (std::vector<std::size_t>{12, 7}));
  EXPECT_GT(r.centre[0].normalized().z(), 0.99);
  EXPECT_GT(r.centre[1].normalized().x(), 0.99);
  // Fewer distinct points than k: as many clusters as points, none empty.
  const KMeansResult three = kmeans({V(0, 0, 1), V(1, 0, 0), V(0, 0, 1), V(0, 1, 0)}, {}, {.k = 6});
  EXPECT_EQ(three.size, (std::vector<std::size_t>{2, 1, 1}));
  EXPECT_EQ(three.inertia, 0.0);
}

// A box tapering upwards: bottom [-2, 2] x [-1.5, 1.5] at z = 0 as n x n quads, top [-1, 1] x
// [-0.5, 0.5] at z = 1 one quad, four sloping sides each one polygon through the bottom's edge
// vertices. Faces outward; face_label: 0 bottom, 1..4 sides, 5 top. The bottom is the largest face.
Mesh tapered_box(int n) {
  Mesh m;
  auto bottom = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) m.vertices.push_back(V(-2 + 4.0 * i / n, -1.5 + 3.0 * j / n, 0));
  const auto top = static_cast<std::uint32_t>(m.vertices.size());
  for (V p : {V(-1, -0.5, 1), V(1, -0.5, 1), V(1, 0.5, 1), V(-1, 0.5, 1)}) m.vertices.push_back(p);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.add_face({bottom(i, j), bottom(i, j + 1), bottom(i + 1, j + 1), bottom(i + 1, j)});  // seen from below
      m.face_label.push_back(0);
    }
  // The bottom's border counter-clockwise seen from above, corner by corner, with the top corner
  // above each bottom corner.
  std::vector<std::vector<std::uint32_t>> sides(4);
  for (int i = 0; i <= n; ++i) sides[0].push_back(bottom(i, 0));
  for (int j = 0; j <= n; ++j) sides[1].push_back(bottom(n, j));
  for (int i = n; i >= 0; --i) sides[2].push_back(bottom(i, n));
  for (int j = n; j >= 0; --j) sides[3].push_back(bottom(0, j));
  for (int s = 0; s < 4; ++s) {
    std::vector<std::uint32_t> face = sides[s];
    face.push_back(top + (s + 1) % 4);
    face.push_back(top + s);
    m.add_face_range(face);
    m.face_label.push_back(1 + s);
  }
  m.add_face({top, top + 1, top + 2, top + 3});
  m.face_label.push_back(5);
  return m;
}

TEST(SetupBase, TheLargestFlatFaceOfABoxIsItsBaseAndOnlyItIsRemoved) {
  const Mesh part = tapered_box(3);
  ASSERT_EQ(mesh_topology(part, mesh_edges(part)).boundary_loops, 0);
  const Outcome r = run(part);
  EXPECT_LT((direction(r.report) - V(0, 0, -1)).norm(), 1e-15);
  EXPECT_EQ(r.report["base_faces"], 9);
  EXPECT_NEAR(r.report["base_area"].get<double>(), 12, 1e-12);
  EXPECT_EQ(r.report["chosen"], 0);
  EXPECT_EQ(r.report["how"], "the cluster of the best objective");
  // Six distinct normals, six clusters, each flat (S = 1); the bottom's Gamma is 1.
  ASSERT_EQ(r.report["clusters"].size(), 6u);
  const auto& best = r.report["clusters"][0];
  EXPECT_NEAR(best["similarity"].get<double>(), 1, 1e-12);
  EXPECT_EQ(best["quantity"], 1.0);
  EXPECT_NEAR(best["objective"].get<double>(), 1, 1e-12);
  for (const auto& c : r.report["clusters"]) EXPECT_NEAR(c["similarity"].get<double>(), 1, 1e-12);
  // Only the bottom went: the sides and the top stay with their labels; the 4 vertices inside
  // the bottom are gone, the rest renumbered in order.
  EXPECT_EQ(r.mesh.face_label, (std::vector<std::int32_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(r.report["vertices_removed"], 4);
  ASSERT_EQ(r.mesh.num_vertices(), 16u);
  EXPECT_EQ(r.mesh.vertices[4], V(-2, -0.5, 0));  // old vertex 4 (i 0, j 1), after 0 .. 3
  EXPECT_EQ(r.mesh.vertices[5], V(2, -0.5, 0));   // old vertex 7: 5 and 6 were inside
  EXPECT_EQ(r.report["facing_kept"]["faces"], 0);
  // The same part in triangles: the same base.
  Mesh triangles;
  triangles.vertices = part.vertices;
  for (std::size_t f = 0; f < part.num_faces(); ++f)
    for (std::size_t k = 1; k + 1 < part.face_size(f); ++k)
      triangles.add_face({part.face(f)[0], part.face(f)[k], part.face(f)[k + 1]});
  const Outcome t = run(triangles);
  EXPECT_LT((direction(t.report) - V(0, 0, -1)).norm(), 1e-15);
  EXPECT_EQ(t.report["base_faces"], 18);
  EXPECT_NEAR(t.report["base_area"].get<double>(), 12, 1e-12);
}

TEST(SetupBase, AGivenDirectionRemovesTheFaceFacingIt) {
  // Quads and triangles: the unit cube's +x side (label 3) as 2 x 2 quads, or as 8 triangles.
  for (const Mesh& cube : {test::quad_box({2, 2, 2}, V(1, 1, 1)), test::cube_mesh(2)}) {
    const Outcome r = run(cube, {{"direction", "1,0,0"}});
    EXPECT_EQ(direction(r.report), V(1, 0, 0));
    EXPECT_EQ(r.report["how"], "given by the parameter direction");
    EXPECT_EQ(r.report["chosen"], -1);
    EXPECT_TRUE(r.report["clusters"].empty());
    EXPECT_NEAR(r.report["base_area"].get<double>(), 1, 1e-12);
    EXPECT_EQ(r.report["plane_offset"], 1.0);
    EXPECT_EQ(r.mesh.num_faces() + r.report["base_faces"].get<std::size_t>(), cube.num_faces());
    EXPECT_EQ(std::count(r.mesh.face_label.begin(), r.mesh.face_label.end(), 3), 0);
    EXPECT_EQ(std::count(cube.face_label.begin(), cube.face_label.end(), 3), r.report["base_faces"].get<int>());
    EXPECT_EQ(r.mesh.num_vertices(), cube.num_vertices() - 1);  // the side's centre
    EXPECT_EQ(mesh_topology(r.mesh, mesh_edges(r.mesh)).boundary_loops, 1);
  }
  EXPECT_EQ(refusal(test::unit_cube(), {{"direction", "1,0"}}),
            "mesh.setup_base: direction must be three numbers \"x,y,z\" (the base's outward normal; \"0,0,0\": find "
            "the base); got \"1,0\"");
}

TEST(SetupBase, ASphereHasNoBaseAndSaysToGiveTheDirection) {
  // Its best flat part is a few faces (of 1280) at the top along a cluster's direction.
  EXPECT_EQ(refusal(test::icosphere(3, 10)),
            "mesh.setup_base: no flat face large enough for a setup base: the largest flat part on the part's "
            "extreme plane, facing (-0.853, 0.468, 0.23), holds 0.324 % of the area, less than min_area 2 %; give "
            "the base's outward normal with the parameter direction");
}

// An open dome (a scan of one side) rests on what it does not show: taken whole, no base.
TEST(SetupBase, AnOpenDomeWithoutAFlatBaseIsTakenWhole) {
  const Mesh sphere = test::icosphere(3, 10);
  const FaceGeometry g = face_geometry(sphere);
  std::vector<bool> upper(sphere.num_faces());
  for (std::size_t f = 0; f < sphere.num_faces(); ++f) upper[f] = g.centroid[f].z() > 0;
  const Mesh dome = keep_faces(sphere, upper);
  const SetupBaseResult r = setup_base(dome, SetupBaseOptions{});
  EXPECT_EQ(r.direction, V::Zero());
  EXPECT_TRUE(r.base_faces.empty());
  EXPECT_EQ(r.mesh.num_faces(), dome.num_faces());
  const MeshEdges e = mesh_edges(dome);
  std::size_t open = 0;
  for (std::size_t i = 0; i < e.size(); ++i) open += e.is_boundary(i);
  EXPECT_GT(open, 0u);
  EXPECT_EQ(r.how, "an open mesh (" + std::to_string(open) +
                       " boundary edges) without a flat base: taken whole, nothing removed");
}

// An L extruded along y (0 .. 2): its profile in x, z runs (0,0) (1,0) (1,1) (3,1) (3,2) (0,2): a
// foot x in [0, 1] under a wider top, so that two faces face down: the foot's bottom at z = 0
// (2 mm^2) and the overhang's underside at z = 1 (4 mm^2, the larger).
Mesh l_part() {
  const std::vector<std::array<double, 2>> profile = {{0, 0}, {1, 0}, {1, 1}, {3, 1}, {3, 2}, {0, 2}};
  Mesh m;
  for (double y : {0.0, 2.0})
    for (const auto& [x, z] : profile) m.vertices.push_back(V(x, y, z));
  m.add_face({0, 1, 2, 3, 4, 5});    // y = 0, seen from -y
  m.add_face({11, 10, 9, 8, 7, 6});  // y = 2
  for (std::uint32_t i = 0; i < 6; ++i) {
    const std::uint32_t j = (i + 1) % 6;
    m.add_face({i, i + 6, j + 6, j});
  }
  return m;
}

TEST(SetupBase, OfTwoFacesFacingTheBaseDirectionOnlyTheExtremeOneIsRemoved) {
  const Mesh part = l_part();
  ASSERT_EQ(mesh_topology(part, mesh_edges(part)).boundary_loops, 0);
  const Outcome r = run(part, {{"direction", "0, 0, -1"}});
  EXPECT_EQ(r.report["base_faces"], 1);
  EXPECT_EQ(r.report["base_area"], 2.0);
  EXPECT_EQ(r.report["plane_offset"], 0.0);
  EXPECT_EQ(r.report["facing_kept"]["faces"], 1);  // the overhang's underside, reported
  EXPECT_EQ(r.report["facing_kept"]["area"], 4.0);
  ASSERT_EQ(r.mesh.num_faces(), 7u);
  EXPECT_EQ(r.mesh.num_vertices(), 12u);
  for (std::size_t f = 0; f < r.mesh.num_faces(); ++f) {
    bool at_zero = true;
    for (std::size_t k = 0; k < r.mesh.face_size(f); ++k) at_zero &= r.mesh.vertices[r.mesh.face(f)[k]].z() == 0;
    EXPECT_FALSE(at_zero) << "face " << f;
  }
}

}  // namespace
}  // namespace scallop
