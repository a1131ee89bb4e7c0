#include "nodes/post/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <sstream>

#include "engine/node.h"
#include "nodes/all_nodes.h"
#include "nodes/types/document.h"
#include "nodes/types/svg.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

Toolpath wave_path(bool uv) {
  Toolpath t;
  t.tool_radius = 2;
  t.scallop_height = 0.05;
  for (int j = 0; j <= 10; ++j) {
    ToolpathPass p;
    for (int i = 0; i <= 40; ++i) {
      double x = i * 0.5, y = j * 1.2;
      p.contact.emplace_back(x, y, std::sin(x / 4));
      p.normal.push_back(Eigen::Vector3d(-std::cos(x / 4) / 4, 0, 1).normalized());
      if (uv) p.uv.emplace_back(i / 40.0, j / 10.0);
    }
    t.passes.push_back(p);
  }
  return t;
}

PointCloud wave_cloud() {
  PointCloud c;
  for (double x = 0; x <= 20; x += 0.3)
    for (double y = 0; y <= 12; y += 0.3) c.points.emplace_back(x, y, std::sin(x / 4));
  return c;
}

std::uint32_t be32(const std::string& s, std::size_t at) {
  return (std::uint32_t(std::uint8_t(s[at])) << 24) | (std::uint32_t(std::uint8_t(s[at + 1])) << 16) |
         (std::uint32_t(std::uint8_t(s[at + 2])) << 8) | std::uint32_t(std::uint8_t(s[at + 3]));
}

std::size_t distinct_colours(const Picture& p) {
  std::set<std::uint32_t> c;
  for (std::size_t i = 0; i + 2 < p.rgb.size(); i += 3) c.insert(p.rgb[i] << 16 | p.rgb[i + 1] << 8 | p.rgb[i + 2]);
  return c.size();
}

TEST(Render, PngHeaderCarriesTheSize) {
  auto cloud = wave_cloud();
  Picture pic = render_path(wave_path(false), &cloud, "top", 400);
  std::string png = encode_png(pic);
  ASSERT_GT(png.size(), 33u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  EXPECT_EQ(png.substr(12, 4), "IHDR");
  EXPECT_EQ(be32(png, 16), 400u);
  EXPECT_EQ(be32(png, 20), std::uint32_t(pic.height));
  EXPECT_NEAR(pic.height, 10 + 10 + 380.0 * 12 / 20, 6);  // aspect of the ~20 × 12 patch
  EXPECT_GT(distinct_colours(pic), 10u);  // cloud shades and both pass colours
}

TEST(Render, IsoAndUvViewsDrawSomething) {
  auto cloud = wave_cloud();
  EXPECT_GT(distinct_colours(render_path(wave_path(false), &cloud, "iso", 300)), 10u);
  EXPECT_GE(distinct_colours(render_path(wave_path(true), nullptr, "uv", 300)), 3u);
  try {
    render_path(wave_path(false), nullptr, "uv", 300);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "no pass carries uv coordinates");
  }
  EXPECT_THROW(render_path(wave_path(false), nullptr, "side", 300), std::invalid_argument);
}

TEST(Render, SvgHasThePasses) {
  std::string svg = render_path_svg(wave_path(false), nullptr, "top", 300);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  std::size_t n = 0;
  for (std::size_t at = svg.find("<polyline"); at != std::string::npos; at = svg.find("<polyline", at + 1)) ++n;
  EXPECT_EQ(n, 11u);
}

TEST(Render, ScallopHeatMapWithColourBar) {
  Simulation sim;
  sim.spacing = 0.1;
  sim.scallop_limit = 0.05;
  sim.gouge_tolerance = 0.001;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 100; ++j) {
      SimSample s{i * 0.1, j * 0.1, 0, 0.01, 0.06 * i / 200.0, 0, true};
      if (i > 190) s.scallop = NAN;  // uncut strip
      sim.samples.push_back(s);
    }
  Picture p = render_scallop(sim, 600);
  EXPECT_EQ(p.width, 600);
  EXPECT_GT(distinct_colours(p), 20u);
  auto px = [&](int x, int y) { std::size_t i = (std::size_t(y) * p.width + x) * 3; return std::array<int, 3>{p.rgb[i], p.rgb[i + 1], p.rgb[i + 2]}; };
  // The right end of the plot (scallop > 1.01 h, then uncut) is red then magenta.
  int y = p.height / 2 < 200 ? 60 : p.height / 2;
  EXPECT_EQ(px(478, y), (std::array<int, 3>{230, 0, 230}));
  std::string svg = render_scallop_svg(sim, 600);
  EXPECT_NE(svg.find("0.0505 mm"), std::string::npos);
}

TEST(Render, APartsScallopColoursEachFaceByItsWorstSample) {
  // The unit square as two triangles seen from both sides: one face's worst sample is uncut
  // (magenta), the other's within the limit; no face is grey, both views and the bar are drawn.
  Mesh square;
  for (Eigen::Vector3d v : {Eigen::Vector3d(0, 0, 0), {10, 0, 0}, {10, 10, 0}, {0, 10, 0}}) square.vertices.push_back(v);
  square.add_face({0, 1, 2});
  square.add_face({0, 2, 3});
  Simulation sim;
  sim.scallop_limit = 0.05, sim.gouge_tolerance = 0.01, sim.spacing = 1;
  sim.samples = {{7, 2, 0, 1, 0.01, 0, true}, {7, 3, 0, 1, NAN, 0, true}, {2, 7, 0, 1, 0.02, 0, true}};
  sim.face = {0, 0, 1};
  const Picture p = render_part_scallop(square, sim, 600);
  EXPECT_EQ(p.width, 600);
  std::size_t magenta = 0, grey = 0;
  for (std::size_t i = 0; i < p.rgb.size(); i += 3) {
    magenta += p.rgb[i] > 100 && p.rgb[i + 1] == 0 && p.rgb[i + 2] > 100;  // shaded magenta
    grey += p.rgb[i] == p.rgb[i + 1] && p.rgb[i + 1] == p.rgb[i + 2] && p.rgb[i] > 120 && p.rgb[i] < 250;
  }
  EXPECT_GT(magenta, 1000u);
  EXPECT_EQ(grey, 0u);
  sim.face = {0, 0, 2};
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { render_part_scallop(square, sim, 600); }),
            "the simulation has a sample on face 2 but the mesh has 2 faces: give the mesh it was simulated on");
  sim.face.clear();
  EXPECT_EQ(test::error_of<std::invalid_argument>([&] { render_part_scallop(square, sim, 600); }),
            "the simulation has no face per sample: give post.simulate_part's");
}

// The output `port` of a node run (test::run_node), of value type T.
template <class T>
std::shared_ptr<const T> output(const std::map<std::string, ValuePtr>& outputs, const std::string& port) {
  auto v = std::dynamic_pointer_cast<const T>(outputs.at(port));
  if (!v) throw std::runtime_error("output '" + port + "' is missing or of another type");
  return v;
}

TEST(RenderNode, DrawsTheScallopMapOfPostSimulatesSimulation) {
  const NodeDecl& simulate = *builtin_registry().find("post.simulate");
  const NodeDecl& render = *builtin_registry().find("post.render");
  auto path = std::make_shared<const Toolpath>(wave_path(false));  // h = 0.05
  auto cloud = std::make_shared<const PointCloud>(wave_cloud());
  // the certificate judged against h = 0.02, not the path's own 0.05
  auto simulated = test::run_node(simulate, {{"scallop", 0.02}}, {{"path", path}, {"cloud", cloud}});
  auto sim = output<Simulation>(simulated, "simulation");
  EXPECT_EQ(sim->report, output<Report>(simulated, "report")->data);
  EXPECT_EQ(sim->scallop_limit, 0.02);
  EXPECT_EQ(sim->gouge_tolerance, 0.001);  // max(e, 0.001), the path's e being 0
  EXPECT_GT(sim->samples.size(), 10000u);
  // the map is that simulation's, drawn against its limits; no path, no cloud, nothing simulated again
  auto drawn = test::run_node(render, {{"view", "scallop"}, {"width", 600}}, {{"simulation", sim}});
  EXPECT_EQ(output<Image>(drawn, "image")->png, render_scallop_png(*sim, 600));
  const std::string svg = output<Svg>(drawn, "svg")->text;
  EXPECT_EQ(svg, render_scallop_svg(*sim, 600));
  EXPECT_NE(svg.find("0.0202 mm"), std::string::npos);  // the colour bar ends at 1.01 h of the simulation
  // the same picture from the simulation's disk-cache form
  std::stringstream bytes;
  sim->serialize(bytes);
  auto cached = std::dynamic_pointer_cast<const Simulation>(Simulation::deserialize(bytes));
  ASSERT_TRUE(cached);
  auto again = test::run_node(render, {{"view", "scallop"}, {"width", 600}}, {{"simulation", cached}});
  EXPECT_EQ(output<Image>(again, "image")->png, output<Image>(drawn, "image")->png);
}

TEST(RenderNode, SaysWhichInputAViewNeeds) {
  const NodeDecl& render = *builtin_registry().find("post.render");
  auto path = std::make_shared<const Toolpath>(wave_path(false));
  auto message = [&](const nlohmann::json& params, std::map<std::string, ValuePtr> inputs) {
    return test::error_of<NodeError>([&] { test::run_node(render, params, std::move(inputs)); });
  };
  EXPECT_EQ(message({{"view", "scallop"}}, {{"path", path}}),
            "view 'scallop' needs the input 'simulation' (post.simulate's)");
  EXPECT_EQ(message({{"view", "iso"}}, {}), "view 'iso' needs the input 'path'");
  EXPECT_EQ(message({{"view", "top"}}, {{"path", path}}), "");
}

}  // namespace
}  // namespace scallop
