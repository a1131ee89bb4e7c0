#include "nodes/mesh/snap_to_reference.h"

#include <gtest/gtest.h>

#include <cmath>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/sharp_edges.h"
#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

bool at_side(double x) { return std::abs(x) < 1e-9 || std::abs(x - 10) < 1e-9; }

// A 10 mm box of 2 mm quads, every vertex pushed off by up to 0.2 mm along each axis, goes back
// onto a 10 mm cube of triangles: corners onto its corners, edge vertices onto its edges, the rest
// onto its sides.
TEST(SnapToReference, AQuadBoxPushedOffGoesBackOntoTheCubeCornersEdgesAndSides) {
  const Mesh cube = test::cube_mesh(10, 10.0);
  const auto cube_features = sharp_edges(cube, mesh_edges(cube), 50).edges;
  ASSERT_EQ(cube_features.size(), 12u * 10u);
  Mesh quads = test::quad_box({5, 5, 5}, Eigen::Vector3d(10, 10, 10));
  quads.feature_edges = sharp_edges(quads, mesh_edges(quads), 50).edges;
  ASSERT_EQ(quads.feature_edges.size(), 12u * 5u);
  const Mesh exact = quads;
  for (std::size_t v = 0; v < quads.num_vertices(); ++v)
    quads.vertices[v] += 0.2 * Eigen::Vector3d(std::sin(3.1 * v), std::cos(1.7 * v), std::sin(0.9 * v + 1));

  const SnapReport r = snap_to_reference(quads, cube, cube_features, 2.0);
  EXPECT_EQ(r.corners, 8u);
  EXPECT_EQ(r.feature_vertices, 12u * 4u);
  EXPECT_EQ(r.surface_vertices, 6u * 16u);
  EXPECT_EQ(r.kept, 0u);
  EXPECT_GT(r.off_surface_max, 0.1);
  EXPECT_LE(r.moved_max, 0.2 * std::sqrt(3.0) + 1e-12);
  for (std::size_t v = 0; v < quads.num_vertices(); ++v) {
    const Eigen::Vector3d& p = quads.vertices[v];
    const Eigen::Vector3d& truth = exact.vertices[v];
    int sides = 0, true_sides = 0;
    for (int k = 0; k < 3; ++k) sides += at_side(p[k]), true_sides += at_side(truth[k]);
    EXPECT_EQ(sides, true_sides) << "vertex " << v << " at " << p.transpose();
    if (true_sides == 3) {
      EXPECT_LT((p - truth).norm(), 1e-12) << "corner " << v;
    }
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(p[k] > -1e-9 && p[k] < 10 + 1e-9);
  }
}

// Two corners that would land on one (the box's top corners all nearest a pyramid's apex) go back
// where they were: the top face would have no area.
TEST(SnapToReference, CornersThatWouldMeetInOneStayWhereTheyWere) {
  Mesh pyramid;
  pyramid.vertices = {{0, 0, 0}, {10, 0, 0}, {10, 10, 0}, {0, 10, 0}, {5, 5, 10}};
  pyramid.add_face({0, 3, 2, 1});
  pyramid.add_face({0, 1, 4});
  pyramid.add_face({1, 2, 4});
  pyramid.add_face({2, 3, 4});
  pyramid.add_face({3, 0, 4});
  const std::vector<std::array<std::uint32_t, 2>> edges{{0, 1}, {1, 2}, {2, 3}, {0, 3}, {0, 4}, {1, 4}, {2, 4}, {3, 4}};
  Mesh box = test::quad_box({1, 1, 1}, Eigen::Vector3d(10, 10, 10));
  box.feature_edges = sharp_edges(box, mesh_edges(box), 50).edges;
  const Mesh before = box;

  const SnapReport r = snap_to_reference(box, pyramid, edges, 12.0);
  EXPECT_EQ(r.corners, 4u);
  EXPECT_EQ(r.kept, 4u);
  for (std::size_t v = 0; v < box.num_vertices(); ++v)
    EXPECT_EQ(box.vertices[v], before.vertices[v]) << "the bottom corners are already the pyramid's";
  EXPECT_DOUBLE_EQ(r.moved_max, 0);
}

TEST(SnapToReference, NearerThanReachOnly) {
  const Mesh cube = test::cube_mesh(2, 10.0);
  Mesh quads = test::quad_box({2, 2, 2}, Eigen::Vector3d(10, 10, 10));
  quads.feature_edges = sharp_edges(quads, mesh_edges(quads), 50).edges;
  for (auto& p : quads.vertices) p += Eigen::Vector3d(0.6, 0.6, 0.6);  // 0.6 mm or more off
  const SnapReport r = snap_to_reference(quads, cube, sharp_edges(cube, mesh_edges(cube), 50).edges, 0.4);
  EXPECT_EQ(r.kept, quads.num_vertices());
  EXPECT_NEAR(r.off_surface_max, 0.6 * std::sqrt(3.0), 1e-9);  // the corner (10.6, 10.6, 10.6)
  EXPECT_DOUBLE_EQ(r.moved_max, 0);
}

TEST(SnapToReference, BadInputIsRefusedWithAClearMessage) {
  Mesh quads = test::unit_cube();
  try {
    snap_to_reference(quads, Mesh{}, {}, 1);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "the reference mesh has no faces");
  }
  try {
    snap_to_reference(quads, test::unit_cube(), {}, 0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "reach must be positive");
  }
}

}  // namespace
}  // namespace scallop
