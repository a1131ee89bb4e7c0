#include "nodes/io/write_toolpath.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace scallop {
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

}  // namespace
}  // namespace scallop
