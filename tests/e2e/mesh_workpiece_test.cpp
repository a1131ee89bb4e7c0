// graphs/mesh-workpiece-contour.json end to end, through the scallop command: the bundled domed
// block (examples/make_part.py) from its STL to a program per clamping, setups.json, the setup
// sheet and the certificate on the whole mesh.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "tests/test_support.h"

namespace scallop {
namespace {

TEST(MeshWorkpiece, TheDomedBlockGetsAProgramPerClampingASetupSheetAndACertificate) {
  test::TempDir dir;
  std::string out;
  const std::filesystem::path o = dir.path / "out";
  const std::string cmd = std::string(SCALLOP_BINARY) + " run " + SCALLOP_SOURCE_DIR +
                          "/graphs/mesh-workpiece-contour.json --no-cache -q --input mesh=" + SCALLOP_SOURCE_DIR +
                          "/examples/domed_block.stl -o " + o.string();
  const int status = test::run_command(cmd, &out);
  const auto report = nlohmann::json::parse(test::read_file(o / "report.json"));
  // The certificate passes (exit 0; 3 would be a failed certificate): the quads snapped back onto
  // the block's edges and corners, the limit lowered by the dome's facet sag, the top's chords
  // within the balls' clearance (0.0548 mm and 0.0527 mm before each of those).
  EXPECT_EQ(status, 0) << out;
  EXPECT_TRUE(report["pass"].get<bool>()) << report["fail_reasons"];
  EXPECT_TRUE(report["fail_reasons"].empty());
  EXPECT_LE(report["scallop_max"].get<double>(), 0.05 * 1.01);  // rim included
  // Top and four sides, each square to the part: five clampings, none at a compound angle.
  const auto setups = nlohmann::json::parse(test::read_file(o / "setups.json"));
  EXPECT_EQ(setups["format"], "scallop-setups/1");
  ASSERT_EQ(setups["setups"].size(), 5u);
  std::set<std::string> names;
  for (const auto& s : setups["setups"]) {
    names.insert(s["name"].get<std::string>().substr(3));
    const std::string program = test::read_file(o / s["gcode"].get<std::string>());
    EXPECT_NE(program.find("\nM2"), std::string::npos) << s["gcode"];
  }
  EXPECT_EQ(names, (std::set<std::string>{"+x", "-x", "+y", "-y", "+z"}));
  // What the certificate measured: the whole surface, 2400 base + 3000 sides + the dome's
  // 2423.89 mm² (the integral of sqrt(1 + |grad z|²) over 60 x 40); the base on the table;
  // nothing unreachable, nothing uncut, no rapid through the part, and no gouge beyond e = 0.01
  // (balls, moves and links are kept r - e/4 off the part's faces; measured 0.0035).
  EXPECT_NEAR(report["surface_area"].get<double>(), 7823.89, 0.05);
  EXPECT_NEAR(report["base_fraction"].get<double>(), 2400 / 7823.89, 1e-5);
  EXPECT_EQ(report["unreachable_fraction"].get<double>(), 0);
  EXPECT_EQ(report["uncut_fraction"].get<double>(), 0);
  EXPECT_EQ(report["rapids_through_part"], 0);
  EXPECT_LE(report["gouge_max"].get<double>(), 0.01);
  for (const auto& s : report["setups"]) EXPECT_LE(s["gouge_max"].get<double>(), 0.01) << s["name"];
  EXPECT_EQ(report["setups"].size(), 5u);
  const std::string sheet = test::read_file(o / "setup_sheet.md");
  EXPECT_NE(sheet.find(report["pass"].get<bool>() ? "**Certificate: PASS.**" : "**Certificate: FAIL"), std::string::npos);
  for (int k = 1; k <= 5; ++k) EXPECT_TRUE(std::filesystem::exists(o / ("setup_" + std::to_string(k) + ".png"))) << k;
  EXPECT_TRUE(std::filesystem::exists(o / "scallop_map.png"));
}

}  // namespace
}  // namespace scallop
