#include "nodes/post/render_mesh.h"

#include <gtest/gtest.h>

#include "nodes/types/document.h"
#include "nodes/types/svg.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

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

TEST(RenderMesh, SvgOfPngEmbedsThePictureAsBase64) {
  Picture p;
  p.width = 3, p.height = 2;
  EXPECT_EQ(svg_of_png(p, "Man"),
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"3\" height=\"2\" viewBox=\"0 0 3 2\">\n"
            "<image width=\"3\" height=\"2\" href=\"data:image/png;base64,TWFu\"/>\n</svg>\n");
  EXPECT_NE(svg_of_png(p, "Ma").find("base64,TWE=\""), std::string::npos);
}

}  // namespace

namespace post_nodes {
NodeDecl make_render_node();
}  // namespace post_nodes
namespace {

TEST(RenderMesh, TheRenderNodeDrawsAMeshWithoutAPath) {
  auto out = test::run_node(post_nodes::make_render_node(), {{"view", "iso"}, {"width", 200}},
                            {{"mesh", std::make_shared<Mesh>(unit_cube())}});
  const std::string& png = std::dynamic_pointer_cast<const Image>(out.at("image"))->png;
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_EQ(encode_png(render_mesh(unit_cube(), {"iso", 200, false, false})), png);
  EXPECT_NE(std::dynamic_pointer_cast<const Svg>(out.at("svg"))->text.find("data:image/png;base64,"), std::string::npos);
}

}  // namespace
}  // namespace scallop
