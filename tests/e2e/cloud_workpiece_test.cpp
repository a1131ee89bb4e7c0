// graphs/workpiece-contour.json end to end, through the scallop command: a clean random cloud of
// the bundled domed block (its STL's triangles, sampled here) to a program per clamping,
// setups.json, the setup sheet and the certificate.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>

#include "nodes/io/read_mesh.h"
#include "nodes/mesh/mesh_topology.h"
#include "nodes/types/cloud.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

// n points spread at random over the mesh's triangles by area, with their faces' normals.
PointCloud sample_triangles(const Mesh& m, int n, unsigned seed) {
  std::vector<double> cumulative;
  double total = 0;
  for (std::size_t f = 0; f < m.num_faces(); ++f) cumulative.push_back(total += 0.5 * face_area_vector(m, f).norm());
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  PointCloud c;
  for (int i = 0; i < n; ++i) {
    const std::size_t f = std::lower_bound(cumulative.begin(), cumulative.end(), u(rng) * total) - cumulative.begin();
    const Eigen::Vector3d &a = m.vertices[m.face(f)[0]], &b = m.vertices[m.face(f)[1]], &d = m.vertices[m.face(f)[2]];
    double s = u(rng), t = u(rng);
    if (s + t > 1) s = 1 - s, t = 1 - t;
    c.points.push_back(a + s * (b - a) + t * (d - a));
    c.normals.push_back(face_area_vector(m, f).normalized());
  }
  return c;
}

TEST(CloudWorkpiece, ACloudOfTheDomedBlockGetsItsEdgesBackAProgramPerClampingAndACertificate) {
  test::TempDir dir;
  const Mesh part = read_mesh(std::string(SCALLOP_SOURCE_DIR) + "/examples/domed_block.stl");
  const std::filesystem::path cloud = dir.path / "domed_block.ply", o = dir.path / "out";
  sample_triangles(part, 60000, 1).write_file(cloud.string());
  std::string out;
  const std::string cmd = std::string(SCALLOP_BINARY) + " run " + SCALLOP_SOURCE_DIR +
                          "/graphs/workpiece-contour.json --no-cache -q --set smooth=0 --set denoise=none --input cloud=" +
                          cloud.string() + " -o " + o.string();
  const int status = test::run_command(cmd, &out);
  ASSERT_TRUE(status == 0 || status == 3) << out;  // 3: the certificate failed (files written all the same)
  const auto report = nlohmann::json::parse(test::read_file(o / "report.json"));
  EXPECT_EQ(status == 0, report["pass"].get<bool>()) << out;
  // The reconstruction's bevels restored: the block's eight corners, its faces as regions (the
  // dome several: a region keeps within half of min_angle of its flattest face).
  const auto sharpen = nlohmann::json::parse(test::read_file(o / "sharpen_report.json"));
  EXPECT_GE(sharpen["regions"], 6);
  EXPECT_EQ(sharpen["corners"], 8);
  EXPECT_GT(sharpen["split_edges"].get<int>(), 0);
  // Every point lies within 0.01 mm of the rebuilt mesh (0.003 measured: the quadrics over the
  // STL's 1 mm facets; the chamfers left points 0.1 mm out before); the envelope's bend
  // allowance stays, at most a spacing.
  const auto envelope = nlohmann::json::parse(test::read_file(o / "envelope_report.json"));
  EXPECT_LT(envelope["residual_max"].get<double>(), 0.01);
  EXPECT_GT(envelope["residual_min"].get<double>(), -0.01);
  EXPECT_GT(envelope["bend_allowance_max"].get<double>(), 0.0);
  EXPECT_LE(envelope["bend_allowance_max"].get<double>(), envelope["spacing_median"].get<double>());
  // The certificate over the whole surface (7823.89 mm² on the STL), the base on the table.
  EXPECT_NEAR(report["surface_area"].get<double>(), 7823.89, 0.005 * 7823.89);
  EXPECT_NEAR(report["base_fraction"].get<double>(), 2400 / 7823.89, 0.01);
  const auto setups = nlohmann::json::parse(test::read_file(o / "setups.json"));
  EXPECT_EQ(setups["format"], "scallop-setups/1");
  ASSERT_GE(setups["setups"].size(), 1u);
  for (const auto& s : setups["setups"]) {
    const std::string program = test::read_file(o / s["gcode"].get<std::string>());
    EXPECT_NE(program.find("\nM2"), std::string::npos) << s["gcode"];
  }
  EXPECT_TRUE(std::filesystem::exists(o / "setup_sheet.md"));
}

}  // namespace
}  // namespace scallop
