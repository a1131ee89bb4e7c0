#include "nodes/post/render_segments.h"

#include <gtest/gtest.h>

#include "nodes/mesh/mesh_topology.h"
#include "nodes/mesh/segment.h"
#include "nodes/types/document.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

std::array<int, 3> pixel(const Picture& p, int x, int y) {
  const std::size_t i = (std::size_t(y) * p.width + x) * 3;
  return {p.rgb[i], p.rgb[i + 1], p.rgb[i + 2]};
}

Segments box_segments() { return segment_shf(test::quad_box({4, 4, 2}, {20, 20, 10}), SegmentOptions{}); }

TEST(RenderSegments, NeighbouringPatchesGetDifferentColours) {
  const Segments s = box_segments();
  ASSERT_EQ(s.patches.size(), 6u);
  const Mesh m = patch_colour_mesh(s);
  const MeshEdges edges = mesh_edges(m);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto f = edges.faces(e)[0], g = edges.faces(e)[1];
    if (s.mesh.face_label[f] != s.mesh.face_label[g]) EXPECT_NE(m.face_label[f], m.face_label[g]);
  }
  // Opposite sides may share a colour: three slots suffice for a box.
  EXPECT_LE(*std::max_element(m.face_label.begin(), m.face_label.end()), 2);
}

TEST(RenderSegments, ClippingEdgesAndAnArrowPerPatchAlongItsDirection) {
  const Segments s = box_segments();
  const auto overlays = segment_overlays(s);
  ASSERT_EQ(overlays.size(), s.clipping_edges.size() + s.patches.size());
  const double length = 0.08 * Eigen::Vector3d(20, 20, 10).norm();
  for (std::size_t i = 0; i < s.patches.size(); ++i) {
    const auto& arrow = overlays[s.clipping_edges.size() + i];
    EXPECT_TRUE(arrow.whole_if_start_seen);
    ASSERT_EQ(arrow.points.size(), 5u);
    EXPECT_NEAR((arrow.points[1] - arrow.points[0] - length * s.patches[i].direction).norm(), 0, 1e-12);
  }
}

TEST(RenderSegments, AnArrowIsDrawnWhereItsFootIsSeenAndNotWhereItIsHidden) {
  const Mesh m = test::unit_cube();
  MeshPictureOptions o;
  o.view = "top", o.width = 120;
  o.overlays = {{{{0.5, 0.5, 1.0}, {0.5, 0.9, 1.0}}, {0, 0, 0}, 2, true}};
  EXPECT_EQ(pixel(render_mesh(m, o), 60, 40), (std::array<int, 3>{0, 0, 0}));
  o.overlays = {{{{0.5, 0.5, 0.0}, {0.5, 0.9, 0.0}}, {0, 0, 0}, 2, true}};  // under the cube's bottom
  EXPECT_NE(pixel(render_mesh(m, o), 60, 40), (std::array<int, 3>{0, 0, 0}));
}

}  // namespace

namespace post_nodes {
NodeDecl make_render_node();
}  // namespace post_nodes
namespace {

TEST(RenderSegments, TheRenderNodeDrawsSegments) {
  auto out = test::run_node(post_nodes::make_render_node(), {{"view", "iso"}, {"width", 300}},
                            {{"segments", std::make_shared<Segments>(box_segments())}});
  EXPECT_EQ(std::dynamic_pointer_cast<const Image>(out.at("image"))->png.substr(1, 3), "PNG");
}

}  // namespace
}  // namespace scallop
