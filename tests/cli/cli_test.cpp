// The scallop command end to end: run, disk cache across processes, batch isolation, validate.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "nodes/io/ply_writer.h"
#include "nodes/types/cloud.h"
#include "tests/test_support.h"

namespace scallop {
namespace {
namespace fs = std::filesystem;

const std::string kScallop = SCALLOP_BINARY;
const std::string kGraph = std::string(SCALLOP_SOURCE_DIR) + "/graphs/prepare-cloud.json";

// A small wavy height-field patch.
void write_patch(const fs::path& path, int n = 40) {
  PointCloud c;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double x = i * 0.5 + 0.01 * std::sin(j), y = j * 0.5;
      c.points.emplace_back(x, y, std::sin(x / 4) * std::cos(y / 5));
    }
  write_ply(path.string(), c);
}

std::vector<nlohmann::json> read_events(const fs::path& path) {
  std::vector<nlohmann::json> events;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) events.push_back(nlohmann::json::parse(line));
  return events;
}

std::map<std::string, std::string> finish_status(const fs::path& events) {
  std::map<std::string, std::string> status;
  for (const auto& e : read_events(events))
    if (e["event"] == "node_finish") status[e["node"]] = e["status"];
  return status;
}

TEST(Cli, RunWritesEachOutputAndASecondProcessReusesTheDiskCache) {
  test::TempDir dir;
  write_patch(dir.path / "patch.ply");
  std::string base = kScallop + " run " + kGraph + " --input cloud=" + (dir.path / "patch.ply").string() +
                     " --cache " + (dir.path / "cache").string() + " -o " + (dir.path / "out").string();
  std::string out;
  ASSERT_EQ(test::run_command(base + " --events " + (dir.path / "e1.jsonl").string(), &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir.path / "out" / "cloud.ply"));
  for (const auto& [node, status] : finish_status(dir.path / "e1.jsonl")) EXPECT_EQ(status, "ok") << node;

  ASSERT_EQ(test::run_command(base + " --explain --events " + (dir.path / "e2.jsonl").string(), &out), 0) << out;
  auto second = finish_status(dir.path / "e2.jsonl");
  ASSERT_EQ(second.size(), 4u);
  for (const auto& [node, status] : second) EXPECT_EQ(status, "cached") << node;
  EXPECT_NE(out.find("cache hit"), std::string::npos) << out;

  ASSERT_EQ(test::run_command(base + " --set knn.k=16 --events " + (dir.path / "e3.jsonl").string(), &out), 0);
  auto third = finish_status(dir.path / "e3.jsonl");
  EXPECT_EQ(third["read"], "cached");
  EXPECT_EQ(third["clean"], "cached");
  EXPECT_EQ(third["knn"], "ok");
  EXPECT_EQ(third["normals"], "ok");
}

TEST(Cli, BatchWithACorruptPartReturnsTheOthersAndNamesIt) {
  test::TempDir dir;
  write_patch(dir.path / "good_a.ply");
  write_patch(dir.path / "good_b.ply", 30);
  test::write_file(dir.path / "broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
  std::string out;
  int rc = test::run_command(kScallop + " batch " + kGraph + " " + (dir.path / "good_a.ply").string() + " " +
                                 (dir.path / "broken.ply").string() + " " + (dir.path / "good_b.ply").string() +
                                 " -j 2 --no-cache -q -o " + (dir.path / "out").string(),
                             &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("error: 1 part(s) failed: broken"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(dir.path / "out" / "good_a" / "cloud.ply"));
  EXPECT_TRUE(fs::exists(dir.path / "out" / "good_b" / "cloud.ply"));
  EXPECT_FALSE(fs::exists(dir.path / "out" / "broken" / "cloud.ply"));
  auto summary = nlohmann::json::parse(test::read_file(dir.path / "out" / "summary.json"));
  ASSERT_EQ(summary["parts"].size(), 3u);
  EXPECT_EQ(summary["parts"][0]["ok"], true);
  EXPECT_EQ(summary["parts"][1]["ok"], false);
  EXPECT_EQ(summary["parts"][1]["part"], "broken");
  EXPECT_NE(summary["parts"][1]["errors"][0].get<std::string>().find("node 'read' (io.read_cloud) failed on part 'broken'"),
            std::string::npos);
  EXPECT_EQ(summary["parts"][2]["ok"], true);
}

TEST(Cli, ValidatePrintsEveryErrorAndExits2) {
  test::TempDir dir;
  test::write_file(dir.path / "bad.json", R"({"scallop_graph": 1, "nodes": [
      {"id": "knn", "type": "cloud.knn", "params": {"k": 0}},
      {"id": "n", "type": "cloud.normal"}]})");
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " validate " + (dir.path / "bad.json").string(), &out), 2);
  EXPECT_NE(out.find("error: nodes[0].params.k: node 'knn': parameter 'k' = 0 is out of range; expected 1 .. 256"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("error: nodes[0].inputs: node 'knn': missing required input 'cloud' (Cloud)"), std::string::npos);
  EXPECT_NE(out.find("error: nodes[1].type: node 'n': unknown node type 'cloud.normal'; expected a registered type "
                     "such as 'cloud.normals' (see 'scallop nodes')"),
            std::string::npos);
  EXPECT_EQ(test::run_command(kScallop + " validate " + kGraph, &out), 0) << out;
}

TEST(Cli, MissingInputFileIsAClearError) {
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kGraph + " --no-cache --input cloud=/nonexistent/x.ply", &out), 2);
  EXPECT_NE(out.find("error: input 'cloud': file '/nonexistent/x.ply' does not exist"), std::string::npos) << out;
}

TEST(Cli, NodesReferenceAndDot) {
  std::string out;
  ASSERT_EQ(test::run_command(kScallop + " nodes cloud.knn --json", &out), 0);
  auto j = nlohmann::json::parse(out);
  EXPECT_EQ(j["type"], "cloud.knn");
  EXPECT_EQ(j["params"][0]["name"], "k");
  ASSERT_EQ(test::run_command(kScallop + " dot " + kGraph, &out), 0);
  EXPECT_NE(out.find("\"knn\" -> \"normals\""), std::string::npos) << out;
}

}  // namespace
}  // namespace scallop

namespace scallop {
namespace {
TEST(Readme, NodeReferenceMatchesTheDeclarations) {
  std::string readme = test::read_file(std::string(SCALLOP_SOURCE_DIR) + "/README.md");
  std::string generated;
  ASSERT_EQ(test::run_command(kScallop + " nodes --markdown 2>/dev/null", &generated), 0);
  auto begin = readme.find("<!-- nodes:begin -->\n"), end = readme.find("<!-- nodes:end -->");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  std::string in_readme = readme.substr(begin + 21, end - begin - 21);
  auto trim = [](std::string s) {
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
    return s;
  };
  EXPECT_TRUE(trim(in_readme) == trim(generated)) << "the README's node reference is out of date: run scripts/update-readme-nodes.sh";
}
}  // namespace
}  // namespace scallop
