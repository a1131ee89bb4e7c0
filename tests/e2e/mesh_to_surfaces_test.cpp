// graphs/mesh-to-surfaces.json end to end, through the scallop command (QuadriFlow in Blender): a
// box standing on its base comes back as B-spline patches of its five other sides, each a height
// field along its side's normal, in a STEP file that reads back with as many faces.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "nodes/io/write_mesh.h"
#include "tests/nodes/mesh/mesh_test_util.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

TEST(MeshToSurfaces, ABoxOnItsBaseGivesItsFiveOtherSidesAsSurfaces) {
  test::TempDir dir;
  // 40 x 30 x 12 mm, triangles as an STL from a scanner or CAD export would be.
  write_mesh(test::quad_box({8, 6, 3}, {40, 30, 12}), (dir.path / "box.stl").string(), "stl");
  std::string out;
  const std::string cmd = std::string(SCALLOP_BINARY) + " run " + SCALLOP_SOURCE_DIR +
                          "/graphs/mesh-to-surfaces.json --no-cache -q --set quads=1500 --set base_direction=0,0,-1 "
                          "--input mesh=" + (dir.path / "box.stl").string() + " -o " + (dir.path / "out").string();
  ASSERT_EQ(test::run_command(cmd, &out), 0) << out;
  const auto report = nlohmann::json::parse(test::read_file(dir.path / "out" / "segments_report.json"));
  const auto step = nlohmann::json::parse(test::read_file(dir.path / "out" / "step_report.json"));
  const auto& patches = report["patches"];
  ASSERT_GE(patches.size(), 5u);
  EXPECT_EQ(step["faces"], patches.size());
  EXPECT_EQ(report["base_direction"], nlohmann::json::array({0.0, 0.0, -1.0}));
  EXPECT_EQ(report["quad_mesh"]["quad_fraction"], 1.0);
  EXPECT_LE(report["fit_max_error"].get<double>(), 0.00125);
  // Every patch a height field along its direction; the five sides each have patches facing
  // them (QuadriFlow may leave a strip of quads bent over an edge: a patch of its own, along a
  // direction between the sides, measured 1 of 9); nothing faces the base.
  std::set<int> sides;
  for (const auto& p : patches) {
    const Eigen::Vector3d d(p["direction"][0], p["direction"][1], p["direction"][2]);
    EXPECT_GT(p["min_normal_dot"].get<double>(), 0.05) << p.dump();
    EXPECT_GT(d.z(), -0.9) << "the base (z = 0) is not machined";
    for (int s = 0; s < 6; ++s)
      if (d.dot(test::cube_side_normal(s)) > 0.999 && p["min_normal_dot"].get<double>() > 0.99) sides.insert(s);
  }
  EXPECT_EQ(sides, (std::set<int>{0, 1, 3, 4, 5}));
  EXPECT_TRUE(std::filesystem::exists(dir.path / "out" / "surfaces.step"));
  EXPECT_TRUE(std::filesystem::exists(dir.path / "out" / "segments.png"));
  EXPECT_TRUE(std::filesystem::exists(dir.path / "out" / "surfaces.png"));
}

}  // namespace
}  // namespace scallop
