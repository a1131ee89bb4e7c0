#include "nodes/mesh/cloud_envelope.h"
#include <algorithm>
#include "nodes/mesh/face_geometry.h"
#include "nodes/mesh/mesh_topology.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "engine/node.h"
#include "nodes/mesh/mesh_distance.h"
#include "nodes/types/cloud.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace mesh_nodes {
NodeDecl make_cloud_envelope_node();
}  // namespace mesh_nodes
namespace {

using V = Eigen::Vector3d;

// Points on the six sides of the box [lo, hi]^3 on a grid `step` apart, keeping off its edges by
// `keep_off` (then every point's nearest place on a smaller concentric cube is inside a side).
std::vector<V> box_side_points(double lo, double hi, double step, double keep_off) {
  std::vector<V> pts;
  const int n = int(std::round((hi - lo) / step));
  for (int axis = 0; axis < 3; ++axis)
    for (double side : {lo, hi})
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          const double a = lo + i * step, b = lo + j * step;
          if (a < lo + keep_off || a > hi - keep_off || b < lo + keep_off || b > hi - keep_off) continue;
          V p;
          p[axis] = side;
          p[(axis + 1) % 3] = a;
          p[(axis + 2) % 3] = b;
          pts.push_back(p);
        }
  return pts;
}

// The outward normals of the sides of [0, 10]^3 that p lies on, summed: one on a side, two on an
// edge, three at a corner.
V sides_sum(const V& p) {
  V n = V::Zero();
  for (int k = 0; k < 3; ++k) n[k] = p[k] < 1e-9 ? -1 : p[k] > 10 - 1e-9 ? 1 : 0;
  return n;
}

// The bend allowance at a vertex of the cube on `sides` sides, points s apart: s sin(theta/2),
// the sine between the vertex normal and its faces' (0 on a side, sin 45 on an edge, sqrt(2/3)
// at a corner).
double bend(double s, int sides) { return s * std::sqrt(1 - 1.0 / sides); }

TEST(CloudEnvelope, PointsOnTheMeshGiveTheMeshItselfBesidesItsEdges) {
  // Points 0.5 apart on the cube's sides: nothing between the two meshes on the sides; along the
  // edges and at the corners the part may still bend sharper between its points.
  const Mesh cube = test::cube_mesh(4, 10);
  const CloudEnvelope e = cloud_envelope(cube, box_side_points(0, 10, 0.5, 0), 16);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    const V sides = sides_sum(cube.vertices[v]);
    const double b = bend(0.5, int(sides.lpNorm<1>()));
    EXPECT_NEAR(e.out[v], b, 1e-12);
    EXPECT_NEAR(e.in[v], b, 1e-12);
    EXPECT_LT((e.outer.vertices[v] - (cube.vertices[v] + b * sides)).norm(), 1e-11);
    EXPECT_LT((e.inner.vertices[v] - (cube.vertices[v] - b * sides)).norm(), 1e-11);
  }
  EXPECT_EQ(e.points_beyond, 0u);
  EXPECT_NEAR(e.bend_allowance_max, bend(0.5, 3), 1e-12);
  EXPECT_NEAR(e.spacing_median, 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(e.max_gap, 2.0);
  EXPECT_EQ(e.unsupported, 0u);
}

// A mesh whose edges are the part's (mesh.sharpen's): the allowance scales with `bend`, 0 leaves
// the points' own distances.
TEST(CloudEnvelope, TheBendAllowanceScalesWithBend) {
  const Mesh cube = test::cube_mesh(4, 10);
  const std::vector<V> pts = box_side_points(0, 10, 0.5, 0);
  const CloudEnvelope none = cloud_envelope(cube, pts, 16, 0, 0.0), twice = cloud_envelope(cube, pts, 16, 0, 2.0);
  EXPECT_EQ(none.bend_allowance_max, 0.0);
  EXPECT_NEAR(twice.bend_allowance_max, 2 * bend(0.5, 3), 1e-12);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    EXPECT_EQ(none.out[v], 0.0);
    EXPECT_LT((none.outer.vertices[v] - cube.vertices[v]).norm(), 1e-12);
    EXPECT_NEAR(twice.out[v], 2 * bend(0.5, int(sides_sum(cube.vertices[v]).lpNorm<1>())), 1e-12);
  }
}

// The cube's own edges as feature edges the part has exactly (mesh.sharpen's): no allowance on
// them, and none beside them either (a vertex sees only the faces on its side); a bend the
// feature edges do not explain keeps its allowance.
// The cube [0, 10]^3 in n by n squares a side, its 12 edges its feature edges.
Mesh cube_with_feature_edges(int n) {
  Mesh cube = test::cube_mesh(n, 10);
  const MeshEdges edges = mesh_edges(cube);
  const FaceGeometry g = face_geometry(cube);
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.faces_on(e) == 2 && angle_deg(g.normal[edges.faces(e)[0]], g.normal[edges.faces(e)[1]]) > 45)
      cube.feature_edges.push_back(edges.edges[e]);
  return cube;
}

TEST(CloudEnvelope, ExactFeatureEdgesNeedNoAllowance) {
  Mesh cube = cube_with_feature_edges(4);
  ASSERT_EQ(cube.feature_edges.size(), 12u * 4);
  const std::vector<V> pts = box_side_points(0, 10, 0.5, 0);
  const CloudEnvelope exact = cloud_envelope(cube, pts, 16, 0, 1.0, true);
  EXPECT_EQ(exact.bend_allowance_max, 0.0);
  // the edges' vertices checked against the sides' points: on them, to rounding
  EXPECT_EQ(exact.vertices_checked, 12u * 3 + 8);
  EXPECT_LT(exact.off_points_max, 1e-12);
  EXPECT_EQ(exact.vertices_without_surface, 0u);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) EXPECT_LT(exact.out[v], 1e-12);
  // the top's front edge (y = 0, z = 10) left out of them: the faces with a corner on it may hide a
  // 90 degree crest, half a chord of two spacings (the points lie 0.5 apart along it); its two
  // corners, where the top's and the front's points (one face of the part there) fit no quadric,
  // are bounded by the two planes those points fit, meeting in the edge: on them, nothing (they
  // got the spacing's allowance before); the other edges' next vertices from them, whose faces'
  // points near them fit a plane, none
  const auto front = [&](const std::array<std::uint32_t, 2>& fe) {
    return cube.vertices[fe[0]].z() == 10 && cube.vertices[fe[1]].z() == 10 && cube.vertices[fe[0]].y() == 0 &&
           cube.vertices[fe[1]].y() == 0;
  };
  cube.feature_edges.erase(std::remove_if(cube.feature_edges.begin(), cube.feature_edges.end(), front),
                           cube.feature_edges.end());
  ASSERT_EQ(cube.feature_edges.size(), 11u * 4);
  const CloudEnvelope partial = cloud_envelope(cube, pts, 16, 0, 1.0, true);
  EXPECT_NEAR(partial.bend_allowance_max, 0.5, 1e-12);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    const V& p = cube.vertices[v];
    const bool corner_side = p.x() == 0 || p.x() == 10;
    const bool crease = !corner_side && ((p.y() == 0 && p.z() >= 7.5) || (p.z() == 10 && p.y() <= 2.5));
    EXPECT_EQ(partial.out[v] > 1e-12, crease) << p.transpose() << " out " << partial.out[v];
    if (crease) EXPECT_NEAR(partial.out[v], 0.5, 1e-12) << p.transpose();
    // a crest: nothing inward
    EXPECT_LT(partial.in[v], 1e-12) << p.transpose() << " in " << partial.in[v];
  }
  EXPECT_EQ(partial.vertices_without_surface, 0u);
  // The corner (0, 0, 10) put 0.05 mm inside the part along each axis: its faces on the top and
  // front now cut across the two planes' line (a bevel, which the corner's bound alone would not
  // lift over the part between its corners), so that side gets the spacing's allowance again; the
  // outer mesh's corner comes back out of the part, onto its corner or beyond.
  std::size_t corner = cube.num_vertices();
  for (std::size_t v = 0; v < cube.num_vertices(); ++v)
    if ((cube.vertices[v] - V(0, 0, 10)).norm() < 1e-12) corner = v;
  ASSERT_LT(corner, cube.num_vertices());
  cube.vertices[corner] = V(0.05, 0.05, 9.95);
  const CloudEnvelope moved = cloud_envelope(cube, pts, 16, 0, 1.0, true);
  EXPECT_EQ(moved.vertices_without_surface, 1u);
  const V outer_corner = moved.outer.vertices[corner];
  EXPECT_TRUE(outer_corner.x() <= 1e-9 || outer_corner.y() <= 1e-9 || outer_corner.z() >= 10 - 1e-9)
      << outer_corner.transpose();
  EXPECT_GE(moved.out[corner], 0.05);
}

// A faceted part, as CAD tessellates a boss: the box [0, 10]^3 with a roof of two facets meeting in a
// 13 degree crest along x = 5.25, its mesh through points 0.5 apart (none on the crest: the faces
// across it cut it by a chord), its box edges feature edges. The outer mesh covers the crest
// between the points, and only a band beside it grows, by at most half a face's longest edge times
// tan 6.5 degrees (the spacing's allowance, 0.5 sin 13 = 0.11 mm on every vertex within 1.5 mm of
// the crest, had kept the balls that far off the block x 5's bosses).
// A 10 mm box 0.5 mm apart whose top is a roof, z = roof_height(x): a crest along y at x = crest,
// each side turned half_turn (radians) down from it; its box edges (over 45 degrees) flagged.
double roof_height(double half_turn, double crest, double x) { return 10 + std::tan(half_turn) * (crest - std::abs(x - crest)); }
Mesh roof_box(double half_turn, double crest) {
  Mesh part = test::cube_mesh(20, 10);
  for (auto& p : part.vertices)
    if (p.z() == 10) p.z() = roof_height(half_turn, crest, p.x());
  const MeshEdges edges = mesh_edges(part);
  const FaceGeometry g = face_geometry(part);
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges.faces_on(e) == 2 && angle_deg(g.normal[edges.faces(e)[0]], g.normal[edges.faces(e)[1]]) > 45)
      part.feature_edges.push_back(edges.edges[e]);
  return part;
}

TEST(CloudEnvelope, ACreaseBetweenThePointsIsCoveredByABandAsThinAsItsFaces) {
  const double half_turn = 6.5 * M_PI / 180, crest = 5.25;
  const auto roof = [&](double x) { return roof_height(half_turn, crest, x); };
  Mesh part = roof_box(half_turn, crest);
  const CloudEnvelope e = cloud_envelope(part, part.vertices, 16, 0, 1.0, true);
  const double diagonal = 0.5 * std::sqrt(2.0), most = diagonal / 2 * std::tan(half_turn);
  EXPECT_LE(e.bend_allowance_max, most + 1e-12);
  EXPECT_GT(e.bend_allowance_max, 0.5 * most);
  for (std::size_t v = 0; v < part.num_vertices(); ++v) {
    const V& p = part.vertices[v];
    if (!(p.z() > 9.99 && p.x() > 0 && p.x() < 10 && p.y() > 0 && p.y() < 10)) continue;  // the roof, off its edges
    if (std::abs(p.x() - crest) > 1.2) EXPECT_LT(e.out[v], 1e-12) << p.transpose();
    EXPECT_LT(e.in[v], 1e-12) << p.transpose();  // a crest: nothing inward
  }
  // The roof, crest included, between the two meshes (1 mm in from the box's edges, where the
  // faces' points bound the edges' vertices instead).
  const MeshDistance outer(e.outer, &part), inner(e.inner, &part);
  for (double x = 4; x <= 6.5; x += 0.05)
    for (double y = 1; y <= 9; y += 0.05) {
      const V p(x, y, roof(x));
      EXPECT_LE(outer.signed_distance(p), 1e-9) << p.transpose();
      EXPECT_GE(inner.signed_distance(p), -1e-9) << p.transpose();
    }
}

// The same roof, one vertex beside the crest 0.001 mm off its point (as where mesh.repair collapsed
// a sliver, or a hole's filling put a corner between the points): that vertex is bounded by its own
// distance, but its faces still cross the crest, and their allowance still reaches their other
// corners. When such faces were left out of the crease rule, the crest stood 0.043 mm outside the
// outer mesh beside the vertex (the block x 5's cloud: 7 samples of the true block up to 0.0265 mm
// out, beside unflagged creases of 18 to 40 degrees).
TEST(CloudEnvelope, AFaceWithACornerOffItsPointStillCoversTheCreaseItCrosses) {
  const double half_turn = 10 * M_PI / 180, crest = 5.25;
  const auto roof = [&](double x) { return roof_height(half_turn, crest, x); };
  Mesh part = roof_box(half_turn, crest);
  std::vector<V> points = part.vertices;
  std::size_t off = points.size();
  for (std::size_t v = 0; v < points.size(); ++v)
    if ((points[v] - V(5, 5, roof(5))).norm() < 1e-9) off = v;
  ASSERT_LT(off, points.size());
  points[off].y() += 0.001;  // along the roof
  const CloudEnvelope e = cloud_envelope(part, points, 16, 0, 1.0, true);
  EXPECT_NEAR(e.gap[off], 0.001, 1e-12);
  const MeshDistance outer(e.outer, &part);
  for (double x = 4.5; x <= 6; x += 0.01)
    for (double y = 4; y <= 6; y += 0.01) {
      const V p(x, y, roof(x));
      EXPECT_LE(outer.signed_distance(p), 1e-9) << p.transpose();
    }
}

// An edge's line of feature edges broken at one place (mesh.sharpen leaves such gaps): the two
// faces of the part are one there, but only the vertices near the break see both faces' points.
// Joined over the whole mesh, every vertex of the top's and the front's edges had got the
// spacing's allowance instead of its exact bound (the block x 5's cloud: 3 131 of 7 286).
// A smooth curved face (a cylinder of radius 5 about the x axis) through points 0.5 apart, jittered
// along it as a random cloud's are: its faces turn up to 10 degrees against the faces around them
// while the part bends 5.7 degrees over a spacing. Where a face's points fit one local surface, its
// allowance is that surface's bulge over the face (a chord's sagitta, l^2 / 8R), not the crease
// its neighbours' turn would allow (l/2 tan(T/2)); and the cylinder still lies between the meshes.
// (Here the largest interior bound is 0.0176 mm against a 1.04 mm diagonal's sagitta of 0.0272; by
// the crease alone it was 0.0532.)
TEST(CloudEnvelope, ACurvedFacesPointsBoundItByTheirSurfaceNotByTheFacesTurn) {
  const double R = 5;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-1, 1);
  Mesh strip;
  const int nx = 20, nt = 12;
  for (int i = 0; i <= nx; ++i)
    for (int j = 0; j <= nt; ++j) {
      const bool rim = i == 0 || i == nx || j == 0 || j == nt;
      const double x = 0.5 * i + (rim ? 0 : 0.15 * jitter(rng)), t = -0.6 + 0.1 * j + (rim ? 0 : 0.03 * jitter(rng));
      strip.vertices.push_back(V(x, R * std::sin(t), R * std::cos(t)));
    }
  const auto at = [&](int i, int j) { return std::uint32_t(i * (nt + 1) + j); };
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < nt; ++j) {
      strip.add_face_range(std::array<std::uint32_t, 3>{at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      strip.add_face_range(std::array<std::uint32_t, 3>{at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  for (int j = 0; j < nt; ++j) strip.feature_edges.push_back({at(0, j), at(0, j + 1)});  // the end x = 0
  const FaceGeometry g = face_geometry(strip);
  ASSERT_GT(g.normal[0].z(), 0.8);  // outward
  double longest = 0;
  for (std::size_t f = 0; f < strip.num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (strip.vertices[strip.face(f)[(k + 1) % 3]] - strip.vertices[strip.face(f)[k]]).norm());
  const CloudEnvelope e = cloud_envelope(strip, strip.vertices, 16, 0, 1.0, true);
  double interior_out = 0;
  for (std::size_t v = 0; v < strip.num_vertices(); ++v)
    if (strip.vertices[v].x() > 1.5 && strip.vertices[v].x() < 8.5 && std::abs(strip.vertices[v].y()) < 2)
      interior_out = std::max(interior_out, e.out[v]);
  const double sagitta = longest * longest / (8 * R);
  EXPECT_LE(interior_out, 1.1 * sagitta) << "longest edge " << longest;
  // Between the meshes: along each ray from the axis, the outer mesh no nearer than the cylinder
  // and the inner no farther.
  const MeshDistance outer(e.outer), inner(e.inner);
  for (double x = 1.5; x <= 8.5; x += 0.05)
    for (double t = -0.4; t <= 0.4; t += 0.01) {
      const V from(x, 0, 0), d(0, std::sin(t), std::cos(t));
      EXPECT_GE(outer.ray_distance(from, d), R - 1e-9) << x << " " << t;
      EXPECT_LE(inner.ray_distance(from, d), R + 1e-9) << x << " " << t;
    }
}

// A vertex off a feature edge a little away from its point (mesh.repair collapsed a sliver's edge
// there) is bounded by that distance: the part passes through the point. Beside an edge the mesh
// does not flag, the points around it fit no quadric, and the bend allowance (here 0.5 mm) had
// kept the balls that far off (0.06 mm beside the fandisk's soft edges).
TEST(CloudEnvelope, AVertexJustOffItsPointIsBoundedByThatDistance) {
  Mesh cube = cube_with_feature_edges(20);
  const auto front_top = [&](const std::array<std::uint32_t, 2>& fe) {
    return cube.vertices[fe[0]].z() == 10 && cube.vertices[fe[1]].z() == 10 && cube.vertices[fe[0]].y() == 0 &&
           cube.vertices[fe[1]].y() == 0;
  };
  cube.feature_edges.erase(std::remove_if(cube.feature_edges.begin(), cube.feature_edges.end(), front_top),
                           cube.feature_edges.end());
  std::size_t moved = cube.num_vertices();
  for (std::size_t v = 0; v < cube.num_vertices(); ++v)
    if ((cube.vertices[v] - V(5, 1, 10)).norm() < 1e-9) moved = v;
  ASSERT_LT(moved, cube.num_vertices());
  cube.vertices[moved].x() += 0.01;  // along the top
  const CloudEnvelope e = cloud_envelope(cube, box_side_points(0, 10, 0.5, 0), 16, 0, 1.0, true);
  EXPECT_NEAR(e.gap[moved], 0.01, 1e-12);
  EXPECT_NEAR(e.out[moved], 0.01, 1e-9);
  EXPECT_NEAR(e.in[moved], 0.01, 1e-9);
}

TEST(CloudEnvelope, ABreakInAnEdgesLineIsBoundedByTheTwoPlanesOfItsFaces) {
  Mesh cube = cube_with_feature_edges(20);
  const V gap_middle(5.25, 0, 10);
  const auto in_gap = [&](const std::array<std::uint32_t, 2>& fe) {
    return (0.5 * (cube.vertices[fe[0]] + cube.vertices[fe[1]]) - gap_middle).norm() < 1e-9;
  };
  cube.feature_edges.erase(std::remove_if(cube.feature_edges.begin(), cube.feature_edges.end(), in_gap),
                           cube.feature_edges.end());
  ASSERT_EQ(cube.feature_edges.size(), 12u * 20 - 1);
  const CloudEnvelope e = cloud_envelope(cube, box_side_points(0, 10, 0.5, 0), 16, 0, 1.0, true);
  EXPECT_EQ(e.vertices_checked, 12u * 19 + 8);
  // the vertices beside the break, whose side's points lie on the top and the front, are bounded
  // by the two planes those fit
  EXPECT_EQ(e.vertices_without_surface, 0u);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    if ((cube.vertices[v] - gap_middle).norm() < 4) continue;
    EXPECT_LT(e.out[v], 1e-12) << cube.vertices[v].transpose();
    EXPECT_LT(e.in[v], 1e-12) << cube.vertices[v].transpose();
  }
}

TEST(CloudEnvelope, AFacesPointsNoQuadricFitsGiveTheAllowanceNotABound) {
  // The cube's top rippled by 0.15 mm (period 2 mm), its points 0.5 apart: a quadric over them
  // misses some by more than a quarter spacing. Its vertices (on the top's edges, or at no
  // point) then get the bend allowance, not a bound of three such misfits: on the fandisk's cloud
  // those moved vertices up to 1.1 mm beside neighbours moved 0.05, and the outer mesh folded.
  Mesh cube = cube_with_feature_edges(4);
  std::vector<V> pts = box_side_points(0, 10, 0.5, 0);
  for (auto& p : pts)
    if (p.z() == 10 && p.x() > 0 && p.x() < 10 && p.y() > 0 && p.y() < 10)
      p.z() += 0.15 * std::sin(M_PI * p.x()) * std::sin(M_PI * p.y());
  const CloudEnvelope e = cloud_envelope(cube, pts, 16, 0, 1.0, true);
  // the top's 25 vertices but the 5 inside it that the ripple leaves on a point (x or y = 5)
  EXPECT_EQ(e.vertices_without_surface, 20u);
  EXPECT_LT(e.off_points_max, 1e-9);  // the flat sides' bounds, on them
  EXPECT_GT(e.bend_allowance_max, 0.0);
}

TEST(CloudEnvelope, AnEdgeTheMeshPutsInsideThePartIsBoundedByItsFacesPoints) {
  // The part is the cube [0, 10]^3, sampled 0.25 apart but no nearer its edges than 0.3 (a cloud
  // has no points on them). The mesh's top front edge (y = 0, z = 10) lies d = 0.02 low, as where
  // mesh.sharpen extrapolated a quadric to the edge: the top's faces beside it tilt down, and the
  // points beside them lie at most 0.4 d above them (0.5 mm faces, no point within 0.3 of the
  // edge), so the points' distances alone leave the part's edge outside the outer mesh. Measured
  // against the top's points (a plane, fitted exactly: no misfit), each such vertex lies d below
  // it, and the front's points put it on the front: out = d, in = 0.
  const double d = 0.02;
  Mesh cube = cube_with_feature_edges(20);
  const auto on_front_edge = [](const V& p) { return p.y() == 0 && p.z() == 10 && p.x() > 0 && p.x() < 10; };
  std::vector<V> pts = box_side_points(0, 10, 0.25, 0.3);
  for (auto& p : cube.vertices)
    if (on_front_edge(p)) p.z() -= d;
  // One of them a point of the cloud as well (a point moved onto the edge, or one the edge runs
  // through): a point on a feature edge belongs to neither face's surface, the vertex is measured all the same.
  const V lowered(5, 0, 10 - d);
  pts.push_back(lowered);
  const CloudEnvelope e = cloud_envelope(cube, pts, 16, 0, 1.0, true);
  EXPECT_EQ(e.vertices_without_surface, 0u);
  EXPECT_NEAR(e.off_points_max, d, 1e-9);
  double residual_max = 0;
  for (double r : e.residual) residual_max = std::max(residual_max, r);
  EXPECT_LT(residual_max, 0.41 * d);  // what the distances alone see
  std::size_t lowered_vertices = 0;
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    if (!on_front_edge(cube.vertices[v] + V(0, 0, d))) continue;
    ++lowered_vertices;
    EXPECT_NEAR(e.out[v], d, 1e-9) << cube.vertices[v].transpose();
    EXPECT_LT(e.in[v], 1e-9) << cube.vertices[v].transpose();
  }
  EXPECT_EQ(lowered_vertices, 19u);
  // The top's faces beside them tilt (by 2.3 degrees), but only through the corners measured
  // above: the points one row in get no bend allowance for it (0.011 mm before v4).
  EXPECT_EQ(e.bend_allowance_max, 0.0);
  // The part's edge lies within the outer mesh.
  const MeshDistance outer(e.outer);
  for (double x = 0.25; x < 10; x += 0.25) EXPECT_LE(outer.signed_distance(V(x, 0, 10)), 1e-9) << x;
}

TEST(CloudEnvelope, AMeshInsideThePartIsGrownByTheDistanceOnEverySideEdgeAndCorner) {
  // The part is the cube [-a, 10 + a]^3, the mesh the cube [0, 10]^3: every point lies a outside.
  // The outer mesh is the cube grown by a (and the bend allowance) on every side, to rounding:
  // faces, edges (along the bisector) and corners (along the diagonal) alike.
  const double a = 0.05;
  const Mesh cube = test::cube_mesh(4, 10);
  const CloudEnvelope e = cloud_envelope(cube, box_side_points(-a, 10 + a, 0.25, 0.1), 16);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    const V sides = sides_sum(cube.vertices[v]);
    const double b = bend(0.25, int(sides.lpNorm<1>()));
    EXPECT_NEAR(e.out[v], a + b, 1e-12);
    EXPECT_NEAR(e.in[v], b, 1e-12);
    EXPECT_LT((e.outer.vertices[v] - (cube.vertices[v] + (a + b) * sides)).norm(), 1e-9) << "vertex " << v;
  }
  for (double r : e.residual) EXPECT_NEAR(r, a, 1e-12);
  EXPECT_EQ(e.points_beyond, 0u);
}

// A cube 10 mm across of two triangles a side (as large as a hole's filling), its points on it but
// for a patch 0.5 above its top, away from its faces' centroids and edges' middles (where the rule
// for a face over a hole in the sampling would see it): those are among no corner's 16 nearest
// points (the corners' bend allowance is 0.2), but each bounds the corners of the face it lies
// nearest, so the outer mesh holds them all.
TEST(CloudEnvelope, PointsOverTheMiddleOfALargeFaceBoundItsCorners) {
  const Mesh cube = test::cube_mesh(1, 10);
  std::vector<V> pts = box_side_points(0, 10, 0.25, 0);
  for (V& p : pts)
    if (p.z() == 10 && std::abs(p.x() - 7.5) <= 0.5 && std::abs(p.y() - 1.5) <= 0.5) p.z() += 0.5;
  const CloudEnvelope e = cloud_envelope(cube, pts, 16);
  EXPECT_EQ(e.points_beyond, 0u);
  const MeshDistance outer(e.outer);
  for (const V& p : pts) EXPECT_LE(outer.signed_distance(p), 1e-9) << p.transpose();
}

TEST(CloudEnvelope, AFaceOverAHoleInTheSamplingMayHideABend) {
  // The part: a roof z = -t |x| with a gentle crest (6 degrees each side) along the y axis. The
  // cloud samples it every 0.25 but not within 0.45 of the crest; the mesh's vertices lie on it at
  // x = -2.5, -1.5, ..., 2.5, so its faces between x = -0.5 and 0.5 bridge the hole flat, 0.5 t
  // below the crest (as the fandisk's cloud left a 0.95 mm face over facets of the part). The
  // spacing's allowance there is about 0.25 sin 3 degrees = 0.013; the faces' gap (0.5) times the
  // slope against their neighbours (t) covers the crest.
  const double t = std::tan(6 * M_PI / 180);
  const auto roof = [&](double x, double y) { return V(x, y, -t * std::abs(x)); };
  Mesh m;
  for (int j = 0; j <= 5; ++j)
    for (int i = 0; i <= 5; ++i) m.vertices.push_back(roof(-2.5 + i, j));
  for (std::uint32_t j = 0; j < 5; ++j)
    for (std::uint32_t i = 0; i < 5; ++i) {
      const std::uint32_t a = 6 * j + i;
      m.add_face({a, a + 1, a + 7});
      m.add_face({a, a + 7, a + 6});
    }
  std::vector<V> pts;
  for (int j = 0; j <= 20; ++j)
    for (int i = -10; i <= 10; ++i)
      if (std::abs(i) >= 2) pts.push_back(roof(0.25 * i, 0.25 * j));
  const CloudEnvelope e = cloud_envelope(m, pts, 16);
  EXPECT_NEAR(e.spacing_median, 0.25, 1e-12);
  for (double r : e.residual) EXPECT_NEAR(r, 0, 1e-12);
  const MeshDistance outer(e.outer);
  for (double y = 1; y <= 4; y += 0.125) EXPECT_LE(outer.signed_distance(roof(0, y)), 1e-9) << y;
  // Faces the sampling covers get nothing: the vertices a face or more from the hole.
  for (std::size_t v = 0; v < m.num_vertices(); ++v)
    if (std::abs(m.vertices[v].x()) > 1) {
      EXPECT_LT(e.out[v], 1e-8) << m.vertices[v].transpose();
    }
  EXPECT_NEAR(e.bend_allowance_max, 0.5 * t, 1e-9);
}

TEST(CloudEnvelope, ABevelledEdgeIsCoveredByTheOuterMesh) {
  // The mesh: the cube [0, 10]^3 with the edge y = z = 10 cut off by the plane y + z = 20 - t
  // (a bevel c = t / sqrt 2 deep), its sides fine triangles as a reconstruction makes them. The
  // part: the whole cube, sampled 0.2 apart, its edges included. The points on that edge lie
  // outside the bevel; every point of the part must lie between the two meshes (to 1e-3 c), and
  // a place of the edge between the points too.
  const double c = 0.1, t = c * std::sqrt(2.0);
  Mesh m = test::cube_mesh(20, 10);
  for (auto& p : m.vertices) {
    const double over = p.y() + p.z() - (20 - t);
    if (over > 0) p -= over / 2 * V(0, 1, 1);  // onto the bevel's plane
  }
  const std::vector<V> part = box_side_points(0, 10, 0.2, 0);
  const CloudEnvelope e = cloud_envelope(m, part, 16);
  const MeshDistance outer(e.outer), inner(e.inner);
  double worst = -INFINITY, worst_inner = INFINITY;
  for (const V& p : part) {
    worst = std::max(worst, outer.signed_distance(p));
    worst_inner = std::min(worst_inner, inner.signed_distance(p));
  }
  EXPECT_LE(worst, 1e-3 * c);
  EXPECT_GE(worst_inner, -1e-3 * c);
  for (double x = 0.1; x < 10; x += 0.2) EXPECT_LE(outer.signed_distance(V(x, 10, 10)), 1e-3 * c) << x;
}

TEST(CloudEnvelope, NoiseOnBothSidesBoundsBothWays) {
  // Points alternately a above and a below the cube's sides: out = in = a at every vertex (and the
  // bend allowance at its edges and corners).
  const double a = 0.02;
  const Mesh cube = test::cube_mesh(4, 10);
  std::vector<V> pts = box_side_points(0, 10, 0.25, 0.1);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const V& p = pts[i];
    pts[i] += (i % 2 ? a : -a) * sides_sum(p);
  }
  const CloudEnvelope e = cloud_envelope(cube, pts, 16);
  const double s = std::hypot(0.25, 2 * a);  // neighbours on the grid, one above, one below
  EXPECT_NEAR(e.spacing_median, s, 1e-12);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    const double b = bend(s, int(sides_sum(cube.vertices[v]).lpNorm<1>()));
    EXPECT_NEAR(e.out[v], a + b, 1e-12);
    EXPECT_NEAR(e.in[v], a + b, 1e-12);
  }
  // With the spread: of each vertex's 16 points m lie a above and 16 - m a below, m = 7, 8 or 9
  // (the grid's checkerboard; ties decide), so their distances' standard deviation about their
  // mean is a sqrt(1 - ((m - 8) / 8)^2): a or a sqrt(63 / 64), added to both bounds c = 1.5 times.
  // At edges and corners points of two or three sides mix (their distances still within a of the
  // mesh): there the spread adds something, at most 1.5 a.
  const CloudEnvelope spread = cloud_envelope(cube, pts, 16, 0, 1, false, 1.5);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) {
    const int sides = int(sides_sum(cube.vertices[v]).lpNorm<1>());
    for (double added : {spread.out[v] - e.out[v], spread.in[v] - e.in[v]}) {
      if (sides == 1)
        EXPECT_TRUE(std::abs(added - 1.5 * a) < 1e-12 || std::abs(added - 1.5 * a * std::sqrt(63.0 / 64)) < 1e-12)
            << cube.vertices[v].transpose() << ": " << added;
      EXPECT_GT(added, 0);
      EXPECT_LE(added, 1.5 * a + 1e-12);
    }
  }
  // Points all a outside (no noise, the mesh inside the part) have no spread.
  const CloudEnvelope offset = cloud_envelope(cube, box_side_points(-a, 10 + a, 0.25, 0.1), 16, 0, 1, false, 1.5);
  const CloudEnvelope plain = cloud_envelope(cube, box_side_points(-a, 10 + a, 0.25, 0.1), 16);
  for (std::size_t v = 0; v < cube.num_vertices(); ++v) EXPECT_NEAR(offset.out[v], plain.out[v], 1e-12);
}

TEST(CloudEnvelope, AVertexFarFromThePointsIsUnsupported) {
  // Only the bottom side is sampled: the top's vertices are 10 from every point.
  const Mesh cube = test::cube_mesh(2, 10);
  std::vector<V> pts;
  for (const V& p : box_side_points(0, 10, 0.5, 0))
    if (p.z() == 0) pts.push_back(p);
  const CloudEnvelope e = cloud_envelope(cube, pts, 8);
  std::size_t far = 0;
  for (const V& p : cube.vertices) far += p.z() > 2;
  EXPECT_EQ(e.unsupported, far);
  EXPECT_DOUBLE_EQ(e.max_gap, 2.0);
}

TEST(CloudEnvelope, BadInputIsRefused) {
  const Mesh cube = test::cube_mesh(2, 10);
  const std::vector<V> pts = box_side_points(0, 10, 2, 0);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(Mesh(), pts, 4); }), "the mesh has no face");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, pts, 0); }), "k must be >= 1");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, {V(0, 0, 0)}, 1); }),
            "the cloud has 1 points, fewer than k = 1 (and 2)");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, {V(0, 0, 0), V(NAN, 0, 0)}, 1); }),
            "the cloud has a point that is not finite");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, pts, 4, -1); }), "max_gap must be >= 0");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, pts, 4, 0, -1); }), "bend must be >= 0");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cloud_envelope(cube, pts, 4, 0, 1, false, -1); }),
            "spread must be >= 0");
}

TEST(CloudEnvelopeNode, ReportsTheBoundsAndWarnsOfUnsupportedVertices) {
  const NodeDecl d = mesh_nodes::make_cloud_envelope_node();
  EXPECT_EQ(d.type, "mesh.cloud_envelope");
  auto cloud = std::make_shared<PointCloud>();
  cloud->points = box_side_points(-0.05, 10.05, 0.25, 0.1);
  auto out = test::run_node(d, {}, {{"mesh", std::make_shared<Mesh>(test::cube_mesh(4, 10))}, {"cloud", cloud}});
  const auto& j = std::dynamic_pointer_cast<const Report>(out.at("report"))->data;
  EXPECT_NEAR(j.at("outward_max").get<double>(), 0.05 + bend(0.25, 3), 1e-12);  // at a corner
  EXPECT_NEAR(j.at("outward_median").get<double>(), 0.05, 1e-12);                 // inside a side
  EXPECT_NEAR(j.at("inward_max").get<double>(), bend(0.25, 3), 1e-12);
  EXPECT_NEAR(j.at("surface_uncertainty").get<double>(), 0.05 + bend(0.25, 3), 1e-12);
  EXPECT_NEAR(j.at("bend_allowance_max").get<double>(), bend(0.25, 3), 1e-12);
  EXPECT_EQ(j.at("points_beyond"), 0);
  EXPECT_EQ(j.at("unsupported_vertices"), 0);
  EXPECT_EQ(j.at("points"), cloud->size());
  ASSERT_TRUE(std::dynamic_pointer_cast<const Mesh>(out.at("outer")));
  ASSERT_TRUE(std::dynamic_pointer_cast<const Mesh>(out.at("inner")));
  auto few = std::make_shared<PointCloud>();
  few->points = {V(0, 0, 0)};
  EXPECT_EQ(test::error_of<NodeError>([&] {
              test::run_node(d, {}, {{"mesh", std::make_shared<Mesh>(test::cube_mesh(2, 10))}, {"cloud", few}});
            }),
            "mesh.cloud_envelope: the cloud has 1 points, fewer than k = 16 (and 2)");
}

}  // namespace
}  // namespace scallop
