#include "nodes/post/render_mesh.h"

#include <gtest/gtest.h>

#include "tests/nodes/mesh/mesh_test_util.h"

namespace scallop {
namespace {

using test::unit_cube;

std::array<int, 3> pixel(const Picture& p, int x, int y) {
  const std::size_t i = (std::size_t(y) * p.width + x) * 3;
  return {p.rgb[i], p.rgb[i + 1], p.rgb[i + 2]};
}

TEST(RenderMesh, TopViewOfACubeFillsASquareWithItsFeatureEdgesRed) {
  Mesh m = unit_cube();
  MeshPictureOptions o;
  o.view = "top";
  o.width = 120;
  Picture plain = render_mesh(m, o);
  EXPECT_EQ(plain.width, 120);
  EXPECT_EQ(plain.height, 120);  // square: 100 px of cube and 10 px of margin each side
  EXPECT_EQ(pixel(plain, 3, 3), (std::array<int, 3>{255, 255, 255}));  // margin
  const auto centre = pixel(plain, 60, 60);
  EXPECT_LT(centre[0], centre[2]);  // the top face: shaded blue-grey, not white
  m.feature_edges = {{{4, 5}}};    // the top face's edge y = 0: the picture's bottom row of the cube
  Picture featured = render_mesh(m, o);
  EXPECT_EQ(pixel(featured, 60, 109), (std::array<int, 3>{217, 13, 13}));
  EXPECT_EQ(pixel(featured, 60, 60), centre);
}

TEST(RenderMesh, LabelsColourTheirFacesAndBadInputIsRefused) {
  Mesh m = unit_cube();
  m.face_label = {0, 1, 2, 3, 4, 5};
  MeshPictureOptions o;
  o.view = "top", o.width = 120, o.by_label = true;
  const auto top = pixel(render_mesh(m, o), 60, 60);  // face 1 (z = 1): label 1, orange
  EXPECT_GT(top[0], top[2]);
  o.view = "side";
  EXPECT_THROW(render_mesh(m, o), std::invalid_argument);
  EXPECT_THROW(render_mesh(Mesh{}, {}), std::invalid_argument);
}

}  // namespace
}  // namespace scallop
