#include "nodes/post/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

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
  SimulationResult sim;
  sim.spacing = 0.1;
  for (int i = 0; i < 200; ++i)
    for (int j = 0; j < 100; ++j) {
      SimSample s{i * 0.1, j * 0.1, 0, 0.01, 0.06 * i / 200.0, 0, true};
      if (i > 190) s.scallop = NAN;  // uncut strip
      sim.samples.push_back(s);
    }
  Picture p = render_scallop(sim, 0.05, 0.001, 600);
  EXPECT_EQ(p.width, 600);
  EXPECT_GT(distinct_colours(p), 20u);
  auto px = [&](int x, int y) { std::size_t i = (std::size_t(y) * p.width + x) * 3; return std::array<int, 3>{p.rgb[i], p.rgb[i + 1], p.rgb[i + 2]}; };
  // The right end of the plot (scallop > 1.01 h, then uncut) is red then magenta.
  int y = p.height / 2 < 200 ? 60 : p.height / 2;
  EXPECT_EQ(px(478, y), (std::array<int, 3>{230, 0, 230}));
  std::string svg = render_scallop_svg(sim, 0.05, 0.001, 600);
  EXPECT_NE(svg.find("0.0505 mm"), std::string::npos);
}

}  // namespace
}  // namespace scallop
