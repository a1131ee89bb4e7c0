#include "nodes/mesh/mesh_distance.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <set>

#include "nodes/geom/triangle.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/self_crossings.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

using V = Eigen::Vector3d;

TEST(MeshDistance, DistancesRaysAndSidesOfTheUnitCube) {
  const MeshDistance cube(test::cube_mesh(3));
  EXPECT_NEAR(cube(V(0.5, 0.5, 1.7)), 0.7, 1e-12);
  EXPECT_NEAR(cube(V(1.3, 1.4, 0.5)), 0.5, 1e-12);  // to the edge x = y = 1
  EXPECT_NEAR(cube(V(0.5, 0.5, 1.7), V(0.5, 0.5, 1)), 0.7, 1e-12);
  EXPECT_NEAR(cube.ray_distance(V(0.5, 0.5, -2), V(0, 0, 1)), 2, 1e-12);
  EXPECT_TRUE(std::isinf(cube.ray_distance(V(0.5, 0.5, 2), V(0, 0, 1))));
  // Signed: inside below zero, by the nearest face or, at an edge or a corner, by the rays.
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 0.9)), -0.1, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 1.1)), 0.1, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(1.3, 1.4, 0.5)), 0.5, 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(2, 2, 2)), std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(cube.signed_distance(V(0.5, 0.5, 0.5)), -0.5, 1e-12);
  // On the faces (a corner, an edge, a vertex of the grid): no side to tell, the distance unsigned.
  for (const V& on : {V(1, 1, 1), V(1, 0.5, 0), V(1.0 / 3, 2.0 / 3, 1), V(1, 1, 1e-10)}) {
    EXPECT_GE(cube.signed_distance(on), 0.0);
    EXPECT_LT(cube.signed_distance(on), 1e-9);
  }
  EXPECT_TRUE(std::isinf(MeshDistance(Mesh()).signed_distance(V(0, 0, 0))));
}

TEST(MeshDistance, BesideEdgesAndCornersConvexOrConcaveTheSideIsThePartsOwn) {
  // An L-shaped prism (a concave edge along x = y = 1, its top and bottom non-convex hexagons
  // fanned from (0, 0)) and the triangulated cube: where the nearest point is on an edge or at a
  // corner, the pseudo-normal there decides the side; every sign must be the solid's own.
  Mesh l;
  const double xy[6][2] = {{0, 0}, {2, 0}, {2, 1}, {1, 1}, {1, 2}, {0, 2}};
  for (double z : {0.0, 1.0})
    for (const auto& c : xy) l.vertices.push_back(V(c[0], c[1], z));
  l.add_face({0, 5, 4, 3, 2, 1});    // bottom, seen from below
  l.add_face({6, 7, 8, 9, 10, 11});  // top
  for (std::uint32_t i = 0; i < 6; ++i) l.add_face({i, (i + 1) % 6, 6 + (i + 1) % 6, 6 + i});
  const auto in_l = [](const V& p) {
    return p.z() > 0 && p.z() < 1 && p.x() > 0 && p.y() > 0 && ((p.x() < 2 && p.y() < 1) || (p.x() < 1 && p.y() < 2));
  };
  const auto in_cube = [](const V& p) { return (p.array() > 0).all() && (p.array() < 1).all(); };
  std::mt19937 rng(5);
  struct Case {
    Mesh mesh;
    std::function<bool(const V&)> inside;
    V lo, hi;
  };
  const Case cases[] = {{l, in_l, V(-0.5, -0.5, -0.5), V(2.5, 2.5, 1.5)},
                        {test::cube_mesh(3), in_cube, V(-0.5, -0.5, -0.5), V(1.5, 1.5, 1.5)}};
  for (const Case& c : cases) {
    const MeshDistance d(c.mesh);
    std::uniform_real_distribution<double> u(0, 1);
    int checked = 0;
    for (int i = 0; i < 20000; ++i) {
      V p = c.lo + (c.hi - c.lo).cwiseProduct(V(u(rng), u(rng), u(rng)));
      if (i % 2) p = p.cwiseMax(c.lo + V::Constant(0.5)).cwiseMin(c.hi - V::Constant(0.5)) +  // near edges
                     0.05 * (V(u(rng), u(rng), u(rng)) - V::Constant(0.5));
      const double dist = d.signed_distance(p);
      if (std::abs(dist) < 1e-6) continue;
      ASSERT_EQ(dist < 0, c.inside(p)) << p.transpose() << " read " << dist;
      ++checked;
    }
    EXPECT_GT(checked, 19000);
  }
  // the concave edge's own neighbourhood, inside and out
  const MeshDistance d(l);
  EXPECT_NEAR(d.signed_distance(V(0.9, 0.9, 0.5)), -std::sqrt(0.02), 1e-12);    // inside, nearest the concave edge
  EXPECT_NEAR(d.signed_distance(V(1.1, 1.1, 0.5)), 0.1, 1e-12);                  // in the notch, two walls
  EXPECT_NEAR(d.signed_distance(V(1.1, 1.1, 1.2)), std::hypot(0.1, 0.2), 1e-12);  // above it, the top's edges
  EXPECT_NEAR(d.signed_distance(V(1.95, 0.95, 0.5)), -0.05, 1e-12);              // inside, a convex edge
  EXPECT_NEAR(d.signed_distance(V(0.95, 1.95, 0.98)), -0.02, 1e-12);             // inside, a corner's faces
  EXPECT_NEAR(d.signed_distance(V(2.3, -0.4, 1.2)), std::sqrt(0.09 + 0.16 + 0.04), 1e-12);  // a corner
}

TEST(MeshDistance, TheClosestFaceIsThePolygonNotItsFannedTriangle) {
  // The unit cube as six quads (face 1 the top z = 1, each fanned into two triangles).
  const Mesh cube = test::unit_cube();
  const MeshDistance d(cube);
  EXPECT_EQ(d.closest_face(V(0.2, 0.7, 1.5)), 1u);
  EXPECT_EQ(d.closest_face(V(0.8, 0.3, 1.5)), 1u);
  EXPECT_EQ(d.closest_face(V(0.5, 0.5, -0.3)), 0u);
  EXPECT_EQ(MeshDistance(Mesh()).closest_face(V(0, 0, 0)), std::numeric_limits<std::size_t>::max());
}

TEST(MeshDistance, AFaceFoldedBackOntoItsNeighbourDoesNotTellTheSide) {
  // The unit cube with its top fanned around (0.5, 0.5, 1), the fan's first triangle split at a
  // point f = (0.5, -0.05, 1) just beyond the top's front edge: the triangle (a, b, f) lies on the
  // plane z = 1 folded back under its neighbours (normal -z, 180 degrees from theirs), as the
  // slivers of block.off do. Still closed, still the cube. Above the fold the point is outside:
  // by the folded triangle's normal alone it read as inside.
  Mesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back(V(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  m.vertices.push_back(V(0.5, 0.5, 1));    // 8: p, the top's centre
  m.vertices.push_back(V(0.5, -0.05, 1));  // 9: f
  m.add_face({0, 2, 3, 1});                 // bottom
  m.add_face({0, 1, 5, 4});                 // front, y = 0
  m.add_face({2, 6, 7, 3});                 // back
  m.add_face({0, 4, 6, 2});                 // x = 0
  m.add_face({1, 3, 7, 5});                 // x = 1
  m.add_face({4, 5, 9});                    // the fold (a, b, f), clockwise from above
  m.add_face({5, 8, 9});
  m.add_face({8, 4, 9});
  m.add_face({5, 7, 8});
  m.add_face({7, 6, 8});
  m.add_face({6, 4, 8});
  const MeshTopology t = mesh_topology(m, mesh_edges(m));
  ASSERT_EQ(t.boundary_loops, 0);
  ASSERT_EQ(t.non_manifold_edges, 0u);
  const MeshDistance d(m);
  EXPECT_NEAR(d.signed_distance(V(0.45, -0.01, 1.3)), 0.3, 1e-12);
  EXPECT_NEAR(d.signed_distance(V(0.3, -0.02, 1.2)), 0.2, 1e-12);
  EXPECT_NEAR(d.signed_distance(V(0.45, 0.02, 0.9)), -0.02, 1e-12);  // inside, nearest the front
  EXPECT_NEAR(d.signed_distance(V(0.5, 0.5, 1.4)), 0.4, 1e-12);
  EXPECT_NEAR(d.signed_distance(V(0.5, 0.5, 0.6)), -0.4, 1e-12);
}

TEST(MeshDistance, AFaceTheMovesTurnedOverIsLeftToTheRays) {
  // The 4 x 4 cube's top with two vertices moved (as mesh.cloud_envelope moves a mesh's vertices
  // along diverging normals): the face (a, b, c) turns over (its normal points down, 130 degrees
  // from its unmoved place, 81-120 from its neighbours) and crosses them. The point a little
  // behind it, where it is the nearest face, is outside the solid the moved faces enclose (three
  // rays agree), but by that face's normal alone it reads inside.
  const Mesh unmoved = test::cube_mesh(4);
  Mesh moved = unmoved;
  const auto index = [&](const Eigen::Vector3d& p) {
    for (std::uint32_t v = 0; v < unmoved.num_vertices(); ++v)
      if ((unmoved.vertices[v] - p).norm() < 1e-12) return v;
    throw std::logic_error("no such vertex");
  };
  const std::uint32_t a = index(V(0.5, 0.25, 1)), b = index(V(0.75, 0.25, 1)), c = index(V(0.5, 0.5, 1));
  moved.vertices[a] = V(0.652, -0.114, 1.296);
  moved.vertices[b] = V(0.302, 0.618, 1.107);
  const Eigen::Vector3d n = (moved.vertices[b] - moved.vertices[a]).cross(moved.vertices[c] - moved.vertices[a]).normalized();
  ASSERT_LT(n.z(), 0);
  const Eigen::Vector3d behind = (moved.vertices[a] + moved.vertices[b] + moved.vertices[c]) / 3 - 0.02 * n;
  const MeshDistance d(moved, &unmoved);
  const std::uint32_t* nearest = moved.face(d.closest_face(behind));
  EXPECT_EQ(std::vector<std::uint32_t>(nearest, nearest + 3), (std::vector<std::uint32_t>{a, b, c}));
  EXPECT_NEAR(d(behind), 0.02, 1e-12);
  EXPECT_NEAR(d.signed_distance(behind), 0.02, 1e-12);
  EXPECT_NEAR(MeshDistance(moved).signed_distance(behind), -0.02, 1e-12);  // the defect, without its place
  // Inside the part and far from the fold, the same answer either way.
  EXPECT_NEAR(d.signed_distance(V(0.5, 0.5, 0.3)), -0.3, 1e-12);
  EXPECT_NEAR(d.signed_distance(V(0.5, 0.5, -0.4)), 0.4, 1e-12);
  // Turned less than 90 degrees, a face may still cross its neighbours: with these two moves
  // (found by a random search over moves of a and b) it turns 43 degrees and its normal reads the
  // point behind it inside, where the rays find it outside.
  for (const auto& [ma, mb] : {std::pair{V(0.823, 0.647, 1.302), V(0.583, 0.571, 1.102)},
                               std::pair{V(0.623, 0.552, 1.214), V(0.440, 0.591, 1.066)}}) {
    Mesh bent = unmoved;
    bent.vertices[a] = ma;
    bent.vertices[b] = mb;
    const Eigen::Vector3d nb = (mb - ma).cross(bent.vertices[c] - ma).normalized();
    EXPECT_LT(nb.z(), std::cos(40 * M_PI / 180));
    const Eigen::Vector3d p = (ma + mb + bent.vertices[c]) / 3 - 0.02 * nb;
    const MeshDistance bd(bent, &unmoved);
    const std::uint32_t* f = bent.face(bd.closest_face(p));
    EXPECT_EQ(std::vector<std::uint32_t>(f, f + 3), (std::vector<std::uint32_t>{a, b, c}));
    EXPECT_NEAR(bd.signed_distance(p), 0.02, 1e-12);
    EXPECT_NEAR(MeshDistance(bent).signed_distance(p), -0.02, 1e-12);  // by the normal
  }
  // Faces that are not the mesh's own are refused.
  const Mesh other = test::cube_mesh(3);
  EXPECT_THROW(MeshDistance(moved, &other), std::invalid_argument);
}

TEST(MeshDistance, AFaceNamedUntrustedIsLeftToTheRays) {
  // The spiked cube: the middle of the top pulled down through the bottom to (2, 2, -1), as a
  // reconstruction tangles at a gap finer than its points. Below the bottom the spike's faces are
  // seen from behind: the point beside the tip, outside the part (winding number 0), reads inside
  // by the nearest face's normal; named untrusted (self_crossings' tangled faces), the rays say
  // outside, and a point inside the cube away from the spike keeps its side.
  std::set<std::size_t> spike;
  const Mesh part = test::spiked_cube(spike);
  const std::vector<std::size_t> tangled = self_crossings(part).tangled;
  const V beside(1.5, 1.95, -0.6);
  const MeshDistance by_normals(part), by_rays(part, nullptr, tangled);
  ASSERT_TRUE(spike.count(by_normals.closest_face(beside)));
  ASSERT_TRUE(std::binary_search(tangled.begin(), tangled.end(), by_normals.closest_face(beside)));
  const double d = by_normals(beside);
  EXPECT_GT(d, 0.1);
  EXPECT_NEAR(by_normals.signed_distance(beside), -d, 1e-12);  // the defect
  EXPECT_NEAR(by_rays.signed_distance(beside), d, 1e-12);
  EXPECT_FALSE(by_rays.inside_by_rays(beside));
  EXPECT_NEAR(by_rays.signed_distance(V(0.5, 0.5, 0.5)), -0.5, 1e-12);
  EXPECT_NEAR(by_rays.signed_distance(V(0.5, 0.5, 4.25)), 0.25, 1e-12);
  // An index past the faces is refused with what it was.
  const std::vector<std::size_t> past = {part.num_faces()};
  try {
    MeshDistance(part, nullptr, past);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()),
              "untrusted face " + std::to_string(part.num_faces()) + " is past the mesh's " + std::to_string(part.num_faces()) + " faces");
  }
}

TEST(MeshDistance, APlacedOneAnswersAsTheMovedMesh) {
  // The cube with a corner cut off (no symmetry to hide a wrong motion), moved rigidly: the
  // placed view of its tree answers every question as a tree of the moved mesh does.
  Mesh m = test::cube_mesh(3);
  for (auto& v : m.vertices)
    if (v.x() > 0.9 && v.y() > 0.9 && v.z() > 0.9) v = V(0.8, 0.8, 0.8);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -2, 0.5);
  Mesh moved = m;
  for (auto& v : moved.vertices) v = R * v + t;
  const MeshDistance base(m), truth(moved);
  const MeshDistance placed = base.placed(R, t);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1, 2);
  for (int i = 0; i < 200; ++i) {
    const V p = R * V(U(rng), U(rng), U(rng)) + t, q = R * V(U(rng), U(rng), U(rng)) + t;
    EXPECT_NEAR(placed(p), truth(p), 1e-12);
    EXPECT_NEAR(placed.signed_distance(p), truth.signed_distance(p), 1e-12);
    EXPECT_LT((placed.closest_point(p) - truth.closest_point(p)).norm(), 1e-12);
    V at, at_truth;  // the face may differ where two hold the nearest point (an edge)
    placed.closest_face(p, at), truth.closest_face(p, at_truth);
    EXPECT_LT((at - at_truth).norm(), 1e-12);
    const V d = (q - p).normalized();
    const double hit = placed.ray_distance(p, d), hit_truth = truth.ray_distance(p, d);
    if (std::isinf(hit_truth)) EXPECT_TRUE(std::isinf(hit));
    else EXPECT_NEAR(hit, hit_truth, 1e-12);
    V where, where_truth;
    std::size_t n = 0;
    EXPECT_NEAR(placed.least_along(p, q, 0.1, 0.3, 1e-6, where, n), truth.least_along(p, q, 0.1, 0.3, 1e-6, where_truth, n), 1e-9);
    EXPECT_LT((where - where_truth).norm(), 1e-6);
  }
  // Placed again: the motions compose.
  const Eigen::Matrix3d R2 = Eigen::AngleAxisd(-1.1, V(0, 1, 0)).toRotationMatrix();
  const V t2(0, 0, 3), p(7, 1, 4);
  Mesh twice = moved;
  for (auto& v : twice.vertices) v = R2 * v + t2;
  EXPECT_NEAR(placed.placed(R2, t2).signed_distance(p), MeshDistance(twice).signed_distance(p), 1e-12);
}

TEST(MeshDistance, TheLeastAlongASegmentIsFoundBetweenItsSamples) {
  const MeshDistance cube(test::cube_mesh(3));
  // Parallel to the edge x = z = 1 at 0.2 from both faces: sqrt(0.08) from y = 0 to 1, more
  // beyond; sampled only every 1.5, the least is found between the samples, to a thousandth of
  // its depth under the floor 1 (more than eps = 1e-6 here).
  V where;
  std::size_t evaluations = 0;
  const double least = cube.least_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, 1, 1e-6, where, evaluations);
  EXPECT_LE(least, std::sqrt(0.08) + 1e-12);
  EXPECT_GE(least, std::sqrt(0.08) - 1e-3 * (1 - std::sqrt(0.08)));
  // With a floor just above it, to eps.
  EXPECT_GE(cube.least_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, std::sqrt(0.08) + 1e-4, 1e-6, where, evaluations),
            std::sqrt(0.08) - 1e-6);
  EXPECT_GE(where.y(), -1e-6);
  EXPECT_LE(where.y(), 1 + 1e-6);
  EXPECT_GT(evaluations, 3u);
  // Through the cube: the centre is 0.5 inside; unsigned, the least is on the faces it crosses.
  EXPECT_NEAR(cube.least_along(V(0.5, 0.5, -1), V(0.5, 0.5, 2), 0.7, 0, 1e-6, where, evaluations), -0.5, 1e-6);
  EXPECT_NEAR(where.z(), 0.5, 1e-3);
  EXPECT_NEAR(cube.least_along(V(0.5, 0.5, -1), V(0.5, 0.5, 2), 0.7, 0.01, 1e-6, where, evaluations, false), 0, 1e-6);
  // Farther than the floor everywhere: a lower bound, no search below it.
  const double far = cube.least_along(V(3, -1, 3), V(3, 2, 3), 0.5, 1, 1e-6, where, evaluations);
  EXPECT_LE(far, 2 * std::sqrt(2.0) + 1e-12);
  EXPECT_GE(far, 1 - 1e-12);
}

TEST(MeshDistance, ASegmentIsClearWhereItsLeastDistanceIsAtLeastTheFloor) {
  const MeshDistance cube(test::cube_mesh(3));
  // Parallel to the edge x = z = 1 at sqrt(0.08) = 0.2828 from it, sampled only every 1.5: the
  // least is between the samples and still seen.
  EXPECT_TRUE(cube.clear_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, 0.2828));
  EXPECT_FALSE(cube.clear_along(V(1.2, -1, 1.2), V(1.2, 2, 1.2), 1.5, 0.2829));
  EXPECT_FALSE(cube.clear_along(V(0.5, 0.5, -1), V(0.5, 0.5, 2), 0.7, 0.01));  // through it
  EXPECT_TRUE(cube.clear_along(V(0.5, 0.5, 1.5), V(0.5, 0.5, 1.5), 0.7, 0.5));  // a point
  // It answers least_along's question: on 400 random segments and floors, the same answer
  // wherever the least is not within 1e-4 of the floor.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 2.5), f(0.05, 1.2);
  int compared = 0;
  for (int k = 0; k < 400; ++k) {
    const V a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng));
    const double floor = f(rng);
    V where;
    std::size_t n = 0;
    const double least = cube.least_along(a, b, 0.1, 2, 1e-7, where, n, false);
    if (std::abs(least - floor) < 1e-4) continue;
    ++compared;
    EXPECT_EQ(cube.clear_along(a, b, 0.25, floor), least >= floor) << k;
  }
  EXPECT_GT(compared, 390);
  // Rising from a ball's centre on the top to 50 above it: where the distance leaves room the
  // march strides, far fewer distances than least_along's samples every step.
  std::size_t marched = 0, sampled = 0;
  V where;
  EXPECT_TRUE(cube.clear_along(V(0.5, 0.5, 1.5), V(0.5, 0.5, 51), 0.125, 0.499, &marched));
  EXPECT_GE(cube.least_along(V(0.5, 0.5, 1.5), V(0.5, 0.5, 51), 0.125, 0.499, 1e-4, where, sampled, false), 0.499);
  EXPECT_LT(marched, 40u);
  EXPECT_GT(sampled, 396u);
  // Points the part holds count: 0.2 under the segment's middle.
  const MeshDistance part = cube.with_points({V(0.5, 0.5, 1.3)});
  EXPECT_FALSE(part.clear_along(V(-1, 0.5, 1.5), V(2, 0.5, 1.5), 0.4, 0.25));
  EXPECT_TRUE(part.clear_along(V(-1, 0.5, 1.5), V(2, 0.5, 1.5), 0.4, 0.19));
  // Placed, asked in the placed frame.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -2, 0.5);
  EXPECT_TRUE(cube.placed(R, t).clear_along(R * V(1.2, -1, 1.2) + t, R * V(1.2, 2, 1.2) + t, 1.5, 0.2828));
  EXPECT_FALSE(cube.placed(R, t).clear_along(R * V(1.2, -1, 1.2) + t, R * V(1.2, 2, 1.2) + t, 1.5, 0.2829));
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cube.clear_along(V(0, std::nan(""), 0), V(0, 0, 0), 1, 1); }),
            "a distance to the mesh was asked at a point that is not finite");
}

TEST(MeshDistance, PointsThePartHoldsBesideItsFacesCountAsPartOfIt) {
  // The unit cube and two points its faces do not hold: one 0.3 above the top's middle, one
  // inside. Distances are to the union: the nearer of the faces and the points.
  const MeshDistance faces(test::cube_mesh(3));
  const MeshDistance part = faces.with_points({V(0.5, 0.5, 1.3), V(0.5, 0.5, 0.5)});
  EXPECT_NEAR(part(V(0.5, 0.5, 2)), 0.7, 1e-12);  // the faces: 1
  EXPECT_NEAR(part(V(0.5, 0.5, 2), V(0.5, 0.5, 1)), 0.7, 1e-12);
  EXPECT_NEAR(part(V(3, 3, 3)), faces(V(3, 3, 3)), 1e-12);
  EXPECT_NEAR(part.signed_distance(V(0.5, 0.5, 1.5)), 0.2, 1e-12);
  EXPECT_NEAR(part.signed_distance(V(0.5, 0.5, 1.1)), 0.1, 1e-12);  // the faces nearer
  EXPECT_NEAR(part.signed_distance(V(0.5, 0.5, 0.6)), -0.4, 1e-12);  // inside: the inner point does not count
  // A segment over the point comes within 0.2 of it, 0.5 of the faces.
  V where;
  std::size_t evaluations = 0;
  const double least = part.least_along(V(-1, 0.5, 1.5), V(2, 0.5, 1.5), 0.4, 1, 1e-6, where, evaluations, false);
  EXPECT_LE(least, 0.2 + 1e-12);
  EXPECT_GE(least, 0.2 - 1e-3 * (1 - 0.2));  // to a thousandth of its depth under the floor
  EXPECT_NEAR(where.x(), 0.5, 1e-3);
  // Rays and the nearest face see the faces only.
  EXPECT_TRUE(std::isinf(part.ray_distance(V(0.5, 0.5, 1.1), V(0, 0, 1))));
  EXPECT_NEAR(part.closest_point(V(0.5, 0.5, 1.4)).z(), 1, 1e-12);
  // Placed, the points move with the faces.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -2, 0.5);
  EXPECT_NEAR(part.placed(R, t)(R * V(0.5, 0.5, 2) + t), 0.7, 1e-12);
  EXPECT_NEAR(faces.placed(R, t).with_points({V(0.5, 0.5, 1.3)})(R * V(0.5, 0.5, 2) + t), 0.7, 1e-12);
  // Without faces, the points alone; none: as before.
  EXPECT_NEAR(MeshDistance(Mesh()).with_points({V(0, 0, 0)})(V(0, 3, 4)), 5, 1e-12);
  EXPECT_NEAR(faces.with_points({})(V(0.5, 0.5, 2)), 1, 1e-12);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { faces.with_points({V(0, std::nan(""), 0)}); }),
            "a point the part holds is not finite");
}

TEST(MeshDistance, PointsHeldWithAMarginCountAsBallsAboutThemAndAddToThoseHeldBefore) {
  // The unit cube, the cloud's point 0.3 above the top's middle, and a point 2 above the top held
  // with a margin of 0.25 (where the part may reach anywhere within 0.25 of it): the distances
  // are to the union of the solid, the point and that ball.
  const MeshDistance faces(test::cube_mesh(3));
  const MeshDistance part = faces.with_points({V(0.5, 0.5, 1.3)}).with_points({V(0.5, 0.5, 3)}, 0.25);
  EXPECT_NEAR(part(V(0.5, 0.5, 2)), 0.7, 1e-12);                   // the cloud's point, held before
  EXPECT_NEAR(part(V(0.5, 0.5, 4)), 0.75, 1e-12);                  // the ball: 1 - 0.25
  EXPECT_NEAR(part.signed_distance(V(0.5, 0.5, 3.1)), -0.15, 1e-12);  // inside the ball
  EXPECT_NEAR(part.placed(Eigen::Matrix3d::Identity(), V(1, 0, 0))(V(1.5, 0.5, 4)), 0.75, 1e-12);
  // A segment passing 0.5 beside the held point comes within 0.25 of the ball.
  V where;
  std::size_t evaluations = 0;
  const double least = part.least_along(V(-1, 0.5, 3.5), V(2, 0.5, 3.5), 0.4, 1, 1e-6, where, evaluations, false);
  EXPECT_LE(least, 0.25 + 1e-12);
  EXPECT_GE(least, 0.25 - 1e-3);
  EXPECT_FALSE(part.clear_along(V(-1, 0.5, 3.5), V(2, 0.5, 3.5), 0.4, 0.26));
  EXPECT_TRUE(part.clear_along(V(-1, 0.5, 3.5), V(2, 0.5, 3.5), 0.4, 0.24));
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { faces.with_points({V(0, 0, 0)}, -1); }),
            "the margin about held points must be >= 0");
}

// A move's least distance in one search: on 400 random segments round the unit cube with a point
// held beside it and a ball held with a margin (short moves, long ones split into pieces, some
// through the solid), the least equals the least over every triangle's and point's nearest pair
// with the segment to 1e-12, `where` is on the segment that far from the part, and it agrees with
// least_along's bound. Placed, asked in the placed frame.
TEST(MeshDistance, TheLeastOnASegmentIsTheExactLeastOverEveryTriangleAndPoint) {
  for (const Mesh& cube : {test::cube_mesh(3), test::icosphere(3, 0.7)}) {  // and a sphere of 1 280 triangles
    const std::vector<V> points{V(0.5, 0.5, 1.3)}, balls{V(-0.6, 0.2, 0.5)};
    const double margin = 0.25;
    const MeshDistance part = MeshDistance(cube).with_points(points).with_points(balls, margin);
    auto brute = [&](const V& a, const V& b) {
      double best = INFINITY;
      V s, t;
      for (std::size_t f = 0; f < cube.num_faces(); ++f)
        for (std::size_t k = 1; k + 1 < cube.face_size(f); ++k)
          best = std::min(best, std::sqrt(closest_segment_triangle(a, b, cube.vertices[cube.face(f)[0]],
                                                                   cube.vertices[cube.face(f)[k]],
                                                                   cube.vertices[cube.face(f)[k + 1]], s, t)));
      for (const V& p : points) best = std::min(best, segment_distance(p, a, b));
      for (const V& p : balls) best = std::min(best, segment_distance(p, a, b) - margin);
      return best;
    };
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.5, 2.5), len(0.01, 0.6);
    for (int k = 0; k < 400; ++k) {
      const V a(u(rng), u(rng), u(rng));
      const V b = k % 4 == 0 ? V(u(rng), u(rng), u(rng)) : V(a + len(rng) * V(u(rng), u(rng), u(rng)).normalized());
      V where;
      const double least = part.least_on_segment(a, b, where);
      EXPECT_NEAR(least, brute(a, b), 1e-12) << k;
      EXPECT_NEAR(segment_distance(where, a, b), 0, 1e-12) << k;
      EXPECT_NEAR(part(where), least, 1e-9) << k;
      V along;
      std::size_t n = 0;
      EXPECT_GE(least + 1e-12, part.least_along(a, b, 0.05, 5, 1e-7, along, n, false)) << k;
    }
  }
  const MeshDistance part = MeshDistance(test::cube_mesh(3)).with_points({V(0.5, 0.5, 1.3)});
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -2, 0.5);
  V where;
  // Parallel to the edge x = z = 1, 0.2 off both faces: sqrt(0.08).
  EXPECT_NEAR(part.placed(R, t).least_on_segment(R * V(1.2, -1, 1.2) + t, R * V(1.2, 0.3, 1.2) + t, where),
              std::sqrt(0.08), 1e-12);
  EXPECT_NEAR(segment_distance(R.transpose() * (where - t), V(1.2, 0, 1.2), V(1.2, 0.3, 1.2)), 0, 1e-12);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { part.least_on_segment(V(0, std::nan(""), 0), V(0, 0, 0), where); }),
            "a distance to the mesh was asked at a point that is not finite");
}

// A ball moved along any direction onto a 1 280-triangle sphere with a point held beside it and a
// ball held with a margin: where it first touches equals the least over every triangle's and
// point's first touch (to 1e-12), at most max, 0 from a start already that near; placed, asked
// in the placed frame; a ball of another radius gets its own search.
TEST(MeshDistance, ABallMovedAlongADirectionStopsWhereItFirstTouches) {
  const Mesh sphere = test::icosphere(3, 3.0);
  const std::vector<V> points{V(0, 0, 3.5)}, balls{V(3.2, 0, 0)};
  const double margin = 0.3;
  const MeshDistance part = MeshDistance(sphere).with_points(points).with_points(balls, margin);
  auto brute = [&](const V& o, const V& d, double r) {
    double best = INFINITY;
    for (std::size_t f = 0; f < sphere.num_faces(); ++f)
      best = std::min(best, ball_touch_triangle(o, d, r, sphere.vertices[sphere.face(f)[0]],
                                                sphere.vertices[sphere.face(f)[1]], sphere.vertices[sphere.face(f)[2]]));
    for (const V& p : points) best = std::min(best, ball_touch_point(o, d, r, p));
    for (const V& p : balls) best = std::min(best, ball_touch_point(o, d, r + margin, p));
    return best;
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1, 1);
  int touched = 0;
  for (int k = 0; k < 300; ++k) {
    const double r = k % 3 == 0 ? 0.5 : 2.0;
    const V o = 9 * V(u(rng), u(rng), u(rng));
    // towards the sphere, roughly, or anywhere
    const V d = (k % 2 ? V(-o + 2 * V(u(rng), u(rng), u(rng))) : V(u(rng), u(rng), u(rng))).normalized();
    if (!(part(o) > r)) {
      EXPECT_EQ(part.touch_along(o, d, r, 100), 0) << k;
      continue;
    }
    const double truth = std::min(100.0, brute(o, d, r));
    const double t = part.touch_along(o, d, r, 100);
    EXPECT_NEAR(t, truth, 1e-12) << k;
    if (truth < 100) {
      ++touched;
      EXPECT_NEAR(part(o + t * d), r, 1e-9) << k;
      EXPECT_NEAR(part.touch_along(o, d, r, 0.5 * truth), 0.5 * truth, 1e-15) << k;
    }
  }
  EXPECT_GT(touched, 100);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, V(1, 2, 3).normalized()).toRotationMatrix();
  const V t(5, -2, 0.5);
  // Straight down onto the top from 10 above: the held point at 3.5 stops it, at 5.5.
  EXPECT_NEAR(part.placed(R, t).touch_along(R * V(0, 0, 10) + t, R * V(0, 0, -1), 2, 100), 4.5, 1e-12);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { part.touch_along(V(0, 0, 10), V(0, 0, -1), 0, 1); }),
            "a ball's radius must be > 0");
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { part.touch_along(V(0, 0, 10), V(0, std::nan(""), -1), 1, 1); }),
            "a distance to the mesh was asked at a point that is not finite");
}

// The nearest point is searched in float boxes (Embree) but found in doubles: on a wavy sheet
// of 5 000 triangles 1 000 mm from the origin (a float's step there is 6e-5 mm), every distance
// equals the least over all triangles to the last bit, at 1e-7 to 10 mm from the faces, with and
// without a hint, and the nearest face and point are those of that least.
TEST(MeshDistance, TheNearestPointIsTheExactLeastOverAllTrianglesFarFromTheOrigin) {
  const V origin(1000, -2000, 500);
  const int n = 51;
  Mesh sheet;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      sheet.vertices.push_back(origin + V(0.2 * i, 0.2 * j, 0.3 * std::sin(0.7 * i) * std::cos(0.5 * j)));
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j + 1 < n; ++j) {
      const std::uint32_t a = i * n + j, b = a + n;
      sheet.add_face({a, b, b + 1});
      sheet.add_face({a, b + 1, a + 1});
    }
  const MeshDistance distance(sheet);
  auto brute = [&](const V& q, std::size_t& face, V& foot) {
    double best = INFINITY;
    for (std::size_t f = 0; f < sheet.num_faces(); ++f) {
      const V c = closest_on_triangle(q, sheet.vertices[sheet.face(f)[0]], sheet.vertices[sheet.face(f)[1]],
                                      sheet.vertices[sheet.face(f)[2]]);
      if ((c - q).norm() < best) best = (c - q).norm(), face = f, foot = c;
    }
    return best;
  };
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 11), off(-7, 1);
  for (int k = 0; k < 400; ++k) {
    // A point of the sheet's box moved off it by 10^-7 to 10 mm, up or down.
    const V on = distance.closest_point(origin + V(u(rng), u(rng), 0));
    const V q = on + std::pow(10.0, off(rng)) * V(0.3 * u(rng), 0.3 * u(rng), k % 2 ? 1 : -1).normalized();
    std::size_t face = 0;
    V foot;
    const double truth = brute(q, face, foot);
    EXPECT_EQ(distance(q), truth) << k;
    EXPECT_EQ(distance(q, on), truth) << k;
    EXPECT_EQ(distance(q, origin + V(5, 5, 0)), truth) << k;  // a hint far from the nearest point
    V at;
    const std::size_t nearest = distance.closest_face(q, at);
    EXPECT_EQ((at - q).norm(), truth) << k;
    if (nearest != face) EXPECT_EQ((foot - q).norm(), truth);  // a tie: an edge both faces hold
  }
}

// CGAL's exact predicates turn a NaN into a GMP rational, and GMP ends the process (SIGFPE): the
// query is refused with an exception the node reports instead.
TEST(MeshDistance, APointThatIsNotFiniteIsRefusedNotACrash) {
  const MeshDistance cube(test::cube_mesh(3));
  const Eigen::Vector3d nan(0.5, std::nan(""), 0.5), inf(0.5, 0.5, HUGE_VAL);
  const std::string said = "a distance to the mesh was asked at a point that is not finite";
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cube(nan); }), said);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cube(inf); }), said);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cube.closest_point(nan); }), said);
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { cube.ray_distance(nan, Eigen::Vector3d::UnitZ()); }), said);
  EXPECT_NEAR(cube(Eigen::Vector3d(0.5, 0.5, 2)), 1, 1e-12);
}

}  // namespace
}  // namespace scallop
