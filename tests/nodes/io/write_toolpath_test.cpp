#include "nodes/io/write_toolpath.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "engine/node.h"
#include "nodes/types/document.h"
#include "tests/test_support.h"

namespace scallop {
namespace io_nodes {
NodeDecl make_write_toolpath_node();
}  // namespace io_nodes
using io_nodes::make_write_toolpath_node;

namespace {

Toolpath two_passes() {
  Toolpath t;
  t.tool_radius = 2;
  t.scallop_height = 0.01;
  t.pattern = "zigzag";
  ToolpathPass a, b;
  a.contact = {{0, 0, 1}, {1, 0, 1}};
  a.normal = {{0, 0, 1}, {0.6, 0, 0.8}};
  b.contact = {{1, 1, 1}};
  b.normal = {{0, 0, 1}};
  b.uv = {{0.5, 0.25}};
  t.passes = {a, b};
  return t;
}

TEST(WriteToolpath, CsvColumns) {
  std::string csv = toolpath_csv(two_passes());
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "pass,index,cx,cy,cz,nx,ny,nz,tx,ty,tz");
  std::getline(in, line);
  std::getline(in, line);
  // tip = contact + r n − r ẑ = (1 + 1.2, 0, 1 + 1.6 − 2)
  EXPECT_EQ(line, "0,1,1,0,1,0.59999999999999998,0,0.80000000000000004,2.2000000000000002,0,0.60000000000000009");
  std::getline(in, line);
  EXPECT_EQ(line.substr(0, 4), "1,0,");
  EXPECT_FALSE(std::getline(in, line));
}

TEST(WriteToolpath, JsonRoundTripsAndFileIsWritten) {
  auto file = std::filesystem::temp_directory_path() / ("scallop_wt_" + std::to_string(::getpid()) + ".json");
  write_toolpath(two_passes(), file.string(), "json");
  std::ifstream in(file);
  auto j = nlohmann::json::parse(in);
  std::filesystem::remove(file);
  EXPECT_EQ(j["pattern"], "zigzag");
  ASSERT_EQ(j["passes"].size(), 2u);
  EXPECT_EQ(j["passes"][0].size(), 2u);
  EXPECT_DOUBLE_EQ(j["passes"][0][1]["tip"][0].get<double>(), 2.2);
  EXPECT_DOUBLE_EQ(j["passes"][1][0]["uv"][1].get<double>(), 0.25);
  EXPECT_FALSE(j["passes"][0][0].contains("uv"));
}

TEST(WriteToolpath, BadFormatAndPath) {
  try {
    write_toolpath(two_passes(), "/tmp/x.txt", "xml");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown tool path format 'xml' (json or csv)");
  }
  EXPECT_THROW(write_toolpath(two_passes(), "/nonexistent-dir/x.csv", "csv"), std::runtime_error);
}

// The node writes inside the run's output folder and refuses a path that would leave it (issue 11).
TEST(WriteToolpath, NodeWritesInsideTheOutputFolderOnly) {
  test::TempDir dir;
  const NodeDecl d = make_write_toolpath_node();
  auto run = [&](const std::string& path) {
    NodeContext ctx(d, "export", "part", {{"path", path}, {"format", "csv"}},
                    {{"path", std::make_shared<Toolpath>(two_passes())}}, nullptr);
    ctx.set_output_dir((dir.path / "out").string());
    d.run(ctx);
    return std::dynamic_pointer_cast<const Report>(ctx.take_outputs().at("report"))->data;
  };
  const auto report = run("paths/toolpath.csv");
  EXPECT_EQ(report["file"], (dir.path / "out" / "paths" / "toolpath.csv").string());
  EXPECT_TRUE(std::filesystem::exists(dir.path / "out" / "paths" / "toolpath.csv"));
  for (const auto& [bad, why] :
       {std::pair<std::string, std::string>{"../x.csv", "'../x.csv' would be written outside the output folder"},
        {"/tmp/x.csv", "'/tmp/x.csv' is absolute: it would be written outside the output folder"}}) {
    try {
      run(bad);
      ADD_FAILURE() << "no error for " << bad;
    } catch (const NodeError& e) {
      EXPECT_EQ(std::string(e.what()), "parameter 'path': " + why + "; expected a relative path inside it, without '..'");
    }
  }
  EXPECT_FALSE(std::filesystem::exists(dir.path / "x.csv"));
}

}  // namespace
}  // namespace scallop
