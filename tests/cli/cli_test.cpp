// The scallop command end to end: run, disk cache across processes, batch isolation, validate.
#include <Eigen/Core>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "nodes/types/ply_writer.h"
#include "nodes/types/cloud.h"
#include "tests/test_support.h"

namespace scallop {
namespace {
namespace fs = std::filesystem;

const std::string kScallop = SCALLOP_BINARY;
const std::string kGraph = std::string(SCALLOP_SOURCE_DIR) + "/graphs/prepare-cloud.json";

// A small wavy height-field patch, raised by dz.
void write_patch(const fs::path& path, int n = 40, double dz = 0) {
  PointCloud c;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double x = i * 0.5 + 0.01 * std::sin(j), y = j * 0.5;
      c.points.emplace_back(x, y, std::sin(x / 4) * std::cos(y / 5) + dz);
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

std::map<std::string, std::string> finish_field(const fs::path& events, const char* field) {
  std::map<std::string, std::string> value;
  for (const auto& e : read_events(events))
    if (e["event"] == "node_finish") value[e["node"]] = e[field];
  return value;
}

TEST(Cli, ADeletedOrSwappedCacheEntryInTheMiddleHealsOnTheNextRun) {
  // read -> clean -> knn -> normals (which reads clean and knn): knn's consumer is cached
  test::TempDir dir;
  write_patch(dir.path / "patch.ply");
  const std::string base = kScallop + " run " + kGraph + " --input cloud=" + (dir.path / "patch.ply").string() +
                           " --cache " + (dir.path / "cache").string() + " --explain -o " + (dir.path / "out").string();
  std::string out;
  ASSERT_EQ(test::run_command(base + " --events " + (dir.path / "e1.jsonl").string(), &out), 0) << out;
  const std::string cloud = test::read_file(dir.path / "out" / "cloud.ply");
  auto key = finish_field(dir.path / "e1.jsonl", "key");
  auto entry = [&](const std::string& node) {
    return dir.path / "cache" / key[node].substr(0, 2) / (key[node] + ".entry");
  };
  ASSERT_TRUE(fs::exists(entry("knn")));

  // was: "node 'knn' (cloud.knn) failed on part 'patch': input 'cloud' is not connected", every run
  fs::remove(entry("knn"));
  ASSERT_EQ(test::run_command(base + " --events " + (dir.path / "e2.jsonl").string(), &out), 0) << out;
  EXPECT_EQ(finish_status(dir.path / "e2.jsonl"),
            (std::map<std::string, std::string>{{"read", "cached"}, {"clean", "cached"}, {"knn", "ok"}, {"normals", "cached"}}));
  EXPECT_EQ(finish_field(dir.path / "e2.jsonl", "why")["clean"], "same type, version, parameters and inputs");
  EXPECT_NE(out.find("cache miss: entry missing; recomputed so that the cache holds it again\n"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(entry("knn")));
  EXPECT_EQ(test::read_file(dir.path / "out" / "cloud.ply"), cloud);

  // clean's cloud (no normals) copied over normals' entry: same port and type, sound checksum
  fs::copy_file(entry("clean"), entry("normals"), fs::copy_options::overwrite_existing);
  ASSERT_EQ(test::run_command(base + " --events " + (dir.path / "e3.jsonl").string(), &out), 0) << out;
  EXPECT_EQ(finish_status(dir.path / "e3.jsonl")["normals"], "ok");
  EXPECT_NE(out.find("cache miss: entry holds another key\n"), std::string::npos) << out;
  EXPECT_EQ(test::read_file(dir.path / "out" / "cloud.ply"), cloud);

  ASSERT_EQ(test::run_command(base + " --events " + (dir.path / "e4.jsonl").string(), &out), 0) << out;
  for (const auto& [node, status] : finish_status(dir.path / "e4.jsonl")) EXPECT_EQ(status, "cached") << node;
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
  EXPECT_EQ(rc, 2) << out;  // the one failure is a malformed input file: bad input
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

TEST(Cli, BatchPartsWithTheSameStemGetTheirOwnFoldersAndSaySo) {
  test::TempDir dir;
  write_patch(dir.path / "good.ply");
  // the same patch as text, with two NaN points cloud.clean drops and must say so
  std::string xyz = "1 nan 2\n";
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) xyz += std::to_string(i * 0.5) + " " + std::to_string(j * 0.5) + " " +
                                        std::to_string(std::sin(i * 0.1) * std::cos(j * 0.1)) + "\n";
  test::write_file(dir.path / "good.xyz", xyz + "inf 0 0\n");
  write_patch(dir.path / "other.ply", 30);
  const std::string ply = (dir.path / "good.ply").string(), txt = (dir.path / "good.xyz").string();
  const fs::path out = dir.path / "out";
  std::string said;
  ASSERT_EQ(test::run_command(kScallop + " batch " + kGraph + " " + ply + " " + (dir.path / "other.ply").string() +
                                  " " + txt + " -j 2 --no-cache -q -o " + out.string(),
                              &said),
            0)
      << said;
  EXPECT_NE(said.find("note: parts " + ply + " and " + txt + " share the name 'good'; their outputs go to " +
                      (out / "good_ply").string() + "/ and " + (out / "good_xyz").string() +
                      "/ and they are named so in messages\n"),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("warning: node 'clean' (cloud.clean) on part 'good_xyz': dropped 2 of 902 points with a NaN "
                      "or infinite coordinate or normal\n"),
            std::string::npos)
      << said;
  EXPECT_TRUE(fs::exists(out / "good_ply" / "cloud.ply"));
  EXPECT_TRUE(fs::exists(out / "good_xyz" / "cloud.ply"));
  EXPECT_TRUE(fs::exists(out / "other" / "cloud.ply"));  // no clash: the stem alone
  EXPECT_FALSE(fs::exists(out / "good"));
  auto summary = nlohmann::json::parse(test::read_file(out / "summary.json"));
  ASSERT_EQ(summary["parts"].size(), 3u);
  EXPECT_EQ(summary["parts"][0]["part"], "good_ply");
  EXPECT_EQ(summary["parts"][2]["part"], "good_xyz");
  EXPECT_EQ(summary["parts"][2]["warnings"][0],
            "node 'clean' (cloud.clean): dropped 2 of 902 points with a NaN or infinite coordinate or normal");

  // the same name and extension in two folders: numbered on
  fs::create_directories(dir.path / "b");
  write_patch(dir.path / "b" / "good.ply", 30);
  const std::string other = (dir.path / "b" / "good.ply").string();
  ASSERT_EQ(test::run_command(kScallop + " batch " + kGraph + " " + ply + " " + other + " --no-cache -q -o " +
                                  (dir.path / "out2").string(),
                              &said),
            0)
      << said;
  EXPECT_NE(said.find("note: parts " + ply + " and " + other + " share the name 'good'; their outputs go to " +
                      (dir.path / "out2" / "good_ply").string() + "/ and " +
                      (dir.path / "out2" / "good_ply_2").string() + "/ and they are named so in messages\n"),
            std::string::npos)
      << said;
  EXPECT_TRUE(fs::exists(dir.path / "out2" / "good_ply_2" / "cloud.ply"));
}

// Plans on the graph input `cloud` (default patch.ply beside the graph) with a 2 mm ball, and
// guards, links and certifies the program against another surface, the input `part`: a part
// lower than the plan is left with stock (the certificate fails), a higher one makes the guard
// lift (warnings), one 10 mm higher needs lifts of more than 3 tool radii (the guard fails).
constexpr const char* kPlanOnOneCutAnother = R"({"scallop_graph": 1, "name": "plan-on-one-cut-another",
 "inputs": {"cloud": {"type": "File", "default": "patch.ply"}, "part": {"type": "File"}},
 "nodes": [
  {"id": "read", "type": "io.read_cloud", "inputs": {"file": "@cloud"}},
  {"id": "knn", "type": "cloud.knn", "inputs": {"cloud": "read.cloud"}},
  {"id": "normals", "type": "cloud.normals", "params": {"orientation": "up"},
   "inputs": {"cloud": "read.cloud", "neighbors": "knn.neighbors"}},
  {"id": "boundary", "type": "cloud.boundary", "inputs": {"cloud": "normals.cloud", "neighbors": "knn.neighbors"}},
  {"id": "loops", "type": "cloud.boundary_order",
   "inputs": {"cloud": "normals.cloud", "neighbors": "knn.neighbors", "loops": "boundary.loops"}},
  {"id": "boundary_map", "type": "param.boundary_map", "params": {"domain": "rectangle"},
   "inputs": {"cloud": "normals.cloud", "loops": "loops.loops"}},
  {"id": "laplacian", "type": "param.laplacian", "inputs": {"cloud": "normals.cloud", "neighbors": "knn.neighbors"}},
  {"id": "harmonic", "type": "param.harmonic",
   "inputs": {"laplacian": "laplacian.laplacian", "map": "boundary_map.map", "loops": "loops.loops", "cloud": "normals.cloud"}},
  {"id": "plan", "type": "path.isoparametric", "params": {"tool_radius": 2, "scallop_height": 0.05, "chord_error": 0.01},
   "inputs": {"cloud": "normals.cloud", "neighbors": "knn.neighbors", "map": "harmonic.map"}},
  {"id": "read_part", "type": "io.read_cloud", "inputs": {"file": "@part"}},
  {"id": "guard", "type": "path.gouge_guard", "inputs": {"path": "plan.toolpath", "cloud": "read_part.cloud"}},
  {"id": "link", "type": "post.link", "inputs": {"path": "guard.toolpath", "cloud": "read_part.cloud"}},
  {"id": "simulate", "type": "post.simulate", "inputs": {"linked": "link.linked", "cloud": "read_part.cloud"}}],
 "outputs": {"report": "simulate.report", "guard_report": "guard.report"}})";

struct PlanOnOneCutAnother {
  test::TempDir dir;
  std::string graph = (dir.path / "g.json").string();
  PlanOnOneCutAnother() {
    test::write_file(graph, kPlanOnOneCutAnother);
    write_patch(dir.path / "patch.ply");
    write_patch(dir.path / "lowered.ply", 40, -0.3);
    write_patch(dir.path / "raised.ply", 40, 0.3);
    write_patch(dir.path / "high.ply", 40, 10);
  }
  std::string run(const std::string& part, const std::string& args) const {
    return kScallop + " run " + graph + " --input part=" + (dir.path / (part + ".ply")).string() + " " + args;
  }
  nlohmann::json report(const std::string& file) const {
    return nlohmann::json::parse(test::read_file(dir.path / file));
  }
};

// What `scallop` prints for a certificate (a Report output with a boolean "pass"), from its JSON.
std::string expected_verdict(const nlohmann::json& rep) {
  std::string line = "certificate 'report': ";
  if (rep["pass"].get<bool>()) {
    line += "pass";
  } else {
    line += "FAIL, do not cut: ";
    for (std::size_t i = 0; i < rep["fail_reasons"].size(); ++i)
      line += (i ? "; " : "") + rep["fail_reasons"][i].get<std::string>();
  }
  char buf[256];
  std::snprintf(buf, sizeof buf, " (scallop_max %.4g, scallop_max_interior %.4g, gouge_max %.4g, uncut_fraction %.4g)",
                rep["scallop_max"].get<double>(), rep["scallop_max_interior"].get<double>(),
                rep["gouge_max"].get<double>(), rep["uncut_fraction"].get<double>());
  return line + buf;
}

TEST(Cli, AFailingCertificatePrintsItsVerdictAndExits3) {
  // the plan is 0.3 mm above the part it cuts: stock everywhere
  PlanOnOneCutAnother g;
  std::string out;
  EXPECT_EQ(test::run_command(g.run("lowered", "--no-cache -q -o " + (g.dir.path / "low").string()), &out), 3) << out;
  auto rep = g.report("low/report.json");
  ASSERT_EQ(rep["pass"], false);
  ASSERT_FALSE(rep["fail_reasons"].empty());
  EXPECT_NE(out.find("\n" + expected_verdict(rep) + "\n"), std::string::npos) << expected_verdict(rep) << "\n" << out;
  EXPECT_EQ(out.find("path.isoparametric"), std::string::npos) << out;  // -q: no per-node lines

  // the part it was planned for: the verdict is printed too (not with -q when it passes), and
  // the exit status follows it
  const int rc = test::run_command(g.run("patch", "--no-cache -o " + (g.dir.path / "same").string()), &out);
  rep = g.report("same/report.json");
  EXPECT_EQ(rc, rep["pass"].get<bool>() ? 0 : 3) << out;
  EXPECT_NE(out.find("\n" + expected_verdict(rep) + "\n"), std::string::npos) << out;
}

TEST(Cli, NodeWarningsReachTheTerminalAndTheEventsFileAlsoFromTheCache) {
  // the part is 0.3 mm above the plan: the guard lifts balls and says so with ctx.warn
  PlanOnOneCutAnother g;
  const std::string args = "-q --cache " + (g.dir.path / "cache").string() + " -o " + (g.dir.path / "out").string();
  std::string out;
  test::run_command(g.run("raised", args + " --events " + (g.dir.path / "e1.jsonl").string()), &out);
  auto said = g.report("out/guard_report.json")["warnings"];
  ASSERT_FALSE(said.empty()) << out;
  const std::string first = said[0].get<std::string>();
  EXPECT_EQ(first.find(" tool positions ("), first.find_first_not_of("0123456789")) << first;
  EXPECT_NE(out.find("warning: node 'guard' (path.gouge_guard) on part 'patch': " + first + "\n"), std::string::npos)
      << out;
  auto warnings_in = [&](const fs::path& events) {
    std::vector<nlohmann::json> w;
    for (const auto& e : read_events(events))
      if (e["event"] == "node_warning") w.push_back(e);
    return w;
  };
  auto w1 = warnings_in(g.dir.path / "e1.jsonl");
  ASSERT_EQ(w1.size(), said.size());
  EXPECT_EQ(w1[0]["node"], "guard");
  EXPECT_EQ(w1[0]["type"], "path.gouge_guard");
  EXPECT_EQ(w1[0]["part"], "patch");
  EXPECT_EQ(w1[0]["message"], first);
  EXPECT_FALSE(w1[0].contains("cached"));

  // a second run takes the guard from the cache and says the same again
  test::run_command(g.run("raised", args + " --events " + (g.dir.path / "e2.jsonl").string()), &out);
  EXPECT_EQ(finish_status(g.dir.path / "e2.jsonl")["guard"], "cached");
  auto w2 = warnings_in(g.dir.path / "e2.jsonl");
  ASSERT_EQ(w2.size(), said.size());
  EXPECT_EQ(w2[0]["message"], first);
  EXPECT_EQ(w2[0]["cached"], true);
  EXPECT_NE(out.find("warning: node 'guard' (path.gouge_guard) on part 'patch': " + first + "\n"), std::string::npos)
      << out;
}

TEST(Cli, BatchCountsFailedCertificatesAndExits3UnlessAPartFailed) {
  PlanOnOneCutAnother g;
  // a certificate with room to spare for the part the plan was made for (h 0.1, gouges to 0.05)
  const std::string loose = " --part-input part --no-cache -q --set simulate.scallop=0.1 --set simulate.chord=0.05";
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " batch " + g.graph + " " + (g.dir.path / "patch.ply").string() + " " +
                                  (g.dir.path / "lowered.ply").string() + loose + " -o " + (g.dir.path / "a").string(),
                              &out),
            3)
      << out;
  auto summary = g.report("a/summary.json");
  EXPECT_EQ(summary["parts_failed"], 0);
  EXPECT_EQ(summary["certificates_failed"], 1);
  EXPECT_EQ(summary["parts"][0]["certificate"], "pass");
  EXPECT_EQ(summary["parts"][0]["certificate_reasons"], nlohmann::json::array());
  EXPECT_EQ(summary["parts"][1]["certificate"], "FAIL");
  EXPECT_EQ(summary["parts"][1]["certificate_reasons"], g.report("a/lowered/report.json")["fail_reasons"]);
  EXPECT_NE(out.find("\npart 'lowered': " + expected_verdict(g.report("a/lowered/report.json")) + "\n"),
            std::string::npos)
      << out;
  EXPECT_EQ(out.find("part 'patch': certificate"), std::string::npos) << out;  // -q: only failing verdicts
  EXPECT_NE(out.find("error: 1 certificate(s) failed, do not cut: lowered\n"), std::string::npos) << out;
  EXPECT_NE(out.find("2 of 2 parts ok, 1 certificate(s) failed; summary in "), std::string::npos) << out;

  // a failed part wins: exit 1; the part whose guard would lift a ball 10 mm says where and why
  EXPECT_EQ(test::run_command(kScallop + " batch " + g.graph + " " + (g.dir.path / "lowered.ply").string() + " " +
                                  (g.dir.path / "high.ply").string() + loose + " -o " + (g.dir.path / "b").string(),
                              &out),
            1)
      << out;
  summary = g.report("b/summary.json");
  EXPECT_EQ(summary["parts_failed"], 1);
  EXPECT_EQ(summary["certificates_failed"], 1);
  EXPECT_EQ(summary["parts"][1]["certificate"], "none");
  const std::string error = summary["parts"][1]["errors"][0];
  EXPECT_EQ(error.rfind("node 'guard' (path.gouge_guard) failed on part 'high': the planned ball at (", 0), 0u) << error;
  EXPECT_NE(error.find(" mm (> 3 tool radii, 6 mm) to clear the cloud's surface: the plan does not follow the "
                       "surface there, e.g. a fold-over of the (u,v) map"),
            std::string::npos)
      << error;
  EXPECT_NE(out.find("error: 1 certificate(s) failed, do not cut: lowered\n"), std::string::npos) << out;
  EXPECT_NE(out.find("error: 1 part(s) failed: high\n"), std::string::npos) << out;
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

TEST(Cli, AGraphCannotWriteOutsideTheOutputFolderNorReadADefaultOutsideItsOwn) {
  test::TempDir dir;
  write_patch(dir.path / "patch.ply");  // beside the graphs' folder, not in it
  auto graph = [&](const std::string& output_name) {
    return R"({"scallop_graph": 1, "inputs": {"cloud": {"type": "File", "default": "../patch.ply"}},
      "nodes": [{"id": "read", "type": "io.read_cloud", "inputs": {"file": "@cloud"}}],
      "outputs": {")" + output_name + R"(": "read.cloud"}})";
  };
  const auto folder = dir.path / "graphs";
  test::write_file(folder / "escape.json", graph("../../escape"));
  test::write_file(folder / "absolute.json", graph((dir.path / "abs").string()));
  test::write_file(folder / "plain.json", graph("cloud"));
  const std::string refused_default = "error: inputs.cloud.default: default file '../patch.ply' lies outside the graph's "
                                      "folder '" + fs::weakly_canonical(folder).string() +
                                      "'; expected a file inside it, or one given with --input cloud=PATH\n";
  std::string out;
  // validate names both; run refuses before anything is read or written
  EXPECT_EQ(test::run_command(kScallop + " validate " + (folder / "escape.json").string(), &out), 2) << out;
  EXPECT_NE(out.find("error: outputs.../../escape: output name '../../escape' is not a plain file name; expected one "
                     "without '/', '\\' or control characters, not '.' or '..'\n"),
            std::string::npos)
      << out;
  EXPECT_NE(out.find(refused_default), std::string::npos) << out;
  const std::string input = " --input cloud=" + (dir.path / "patch.ply").string();
  EXPECT_EQ(test::run_command(kScallop + " run " + (folder / "escape.json").string() + input + " --no-cache -q -o " +
                                  (dir.path / "out" / "a").string(), &out), 2) << out;
  EXPECT_EQ(test::run_command(kScallop + " run " + (folder / "absolute.json").string() + input + " --no-cache -q -o " +
                                  (dir.path / "out" / "a").string(), &out), 2) << out;
  EXPECT_NE(out.find("error: outputs." + (dir.path / "abs").string() + ": output name '"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.path / "escape.ply"));
  EXPECT_FALSE(fs::exists(dir.path / "abs.ply"));

  // the default outside the graph's folder: refused, unless the file is given on the command line
  EXPECT_EQ(test::run_command(kScallop + " run " + (folder / "plain.json").string() + " --no-cache -q -o " +
                                  (dir.path / "out" / "b").string(), &out), 2) << out;
  EXPECT_EQ(out, refused_default);
  EXPECT_EQ(test::run_command(kScallop + " run " + (folder / "plain.json").string() + input + " --no-cache -q -o " +
                                  (dir.path / "out" / "b").string(), &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir.path / "out" / "b" / "cloud.ply"));
}

TEST(Cli, AGraphNestedTooDeepIsRefusedAtOnce) {
  // 100 000 levels in 200 KB: validate took 4.3 GB and 49 s before bad_alloc
  test::TempDir dir;
  test::write_file(dir.path / "deep.json", "{\"scallop_graph\": 1, \"nodes\": " + std::string(100000, '[') +
                                               std::string(100000, ']') + "}");
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " validate " + (dir.path / "deep.json").string(), &out), 2) << out;
  EXPECT_EQ(out, "error: " + (dir.path / "deep.json").string() +
                     ": line 1, column 94: objects and arrays nested more than 64 levels deep; expected at most 64\n");
}

TEST(Cli, MissingInputFileIsAClearError) {
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kGraph + " --no-cache --input cloud=/nonexistent/x.ply", &out), 2);
  EXPECT_NE(out.find("error: input 'cloud': file '/nonexistent/x.ply' does not exist"), std::string::npos) << out;
}

// ---------------------------------------------------------------- issue 11: bad input

const std::string kZigzag = std::string(SCALLOP_SOURCE_DIR) + "/graphs/isoparametric-zigzag.json";

TEST(Cli, MalformedOrOutOfRangeInputFilesExit2) {
  // a malformed file was exit 1 ("a node failed"); the README says 2, bad input
  test::TempDir dir;
  test::write_file(dir.path / "broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kGraph + " --input cloud=" + (dir.path / "broken.ply").string() +
                                  " --no-cache -q -o " + (dir.path / "out").string(), &out), 2) << out;
  EXPECT_NE(out.find("error: node 'read' (io.read_cloud) failed on part 'broken': " + (dir.path / "broken.ply").string() +
                     ": line 4: header ends without 'end_header'"),
            std::string::npos) << out;
  // 1e300 was reported by the normals as "coincident or collinear"
  std::string xyz;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) xyz += std::to_string(i) + " " + std::to_string(j) + " 0\n";
  test::write_file(dir.path / "far.xyz", xyz + "1e300 0 0\n");
  EXPECT_EQ(test::run_command(kScallop + " run " + kGraph + " --input cloud=" + (dir.path / "far.xyz").string() +
                                  " --no-cache -q -o " + (dir.path / "out").string(), &out), 2) << out;
  EXPECT_NE(out.find("error: node 'read' (io.read_cloud) failed on part 'far': " + (dir.path / "far.xyz").string() +
                     ": point 400 at (1e+300, 0, 0): coordinates out of range (beyond 1e9 mm); the file is damaged "
                     "or its scale is wrong\n"),
            std::string::npos) << out;
}

// A wavy patch `size` mm wide (n x n points), written as XYZ divided by `unit` (1000: metres).
void write_wavy(const fs::path& path, double size, int n, double unit = 1) {
  std::string s;
  char buf[128];
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = size * i / (n - 1), y = size * j / (n - 1), z = 3 * std::sin(x / 20) * std::cos(y / 25);
      std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", x / unit, y / unit, z / unit);
      s += buf;
    }
  test::write_file(path, s);
}

TEST(Cli, ACloudInMetresIsWarnedAtTheReaderAndRefusedByThePlanner) {
  // a 100 mm part in metres: 0.1 mm wide under a 4 mm ball got exit 0 and a passing certificate
  test::TempDir dir;
  write_wavy(dir.path / "metres.xyz", 100, 60, 1000);
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kZigzag + " --input cloud=" + (dir.path / "metres.xyz").string() +
                                  " --no-cache -q -o " + (dir.path / "out").string(), &out), 1) << out;
  EXPECT_NE(out.find("warning: node 'read' (io.read_cloud) on part 'metres': the cloud is 0.1 mm across with points "
                     "0.0017 mm apart: is it in metres? coordinates are read as mm; set read.scale to 1000\n"),
            std::string::npos) << out;
  EXPECT_NE(out.find("error: node 'plan' (path.isoparametric) failed on part 'metres': the part is 0.1 mm wide, "
                     "smaller than the 8 mm ball (tool_radius 4 mm): is the cloud in metres? set the reader's scale "
                     "to 1000 (--set read.scale=1000 with the shipped graphs), or use a smaller tool\n"),
            std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.path / "out" / "gcode.ngc"));
}

TEST(Cli, AFloorBesideASteepWallIsCertifiedUpToWhereTheBallReachesAndTheRestReported) {
  // A floor flat to x = 40 and a wall rising 10 mm by x = 41 (84 degrees), a ledge beyond it.
  // Trimmed at the default 75 degrees, the field beyond the floor's last points was extrapolated
  // over the wall (54 mm high 1 mm past them) and the guard refused the ball beside it for a lift
  // of 42.65 mm. The wall is now what cloud.trim_steep left out: the guard moves the balls that
  // would reach it sideways off it onto the floor, the program keeps off the exact wall, the floor
  // within the ball's reach of the wall is reported as not reachable by this ball, and the rest is
  // certified (exit 0).
  test::TempDir dir;
  PointCloud c;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(0, 43), uy(0, 30), u01(0, 1);
  for (int i = 0; i < 30000; ++i) {
    const double x = ux(rng);
    c.points.emplace_back(x, uy(rng), 10 * std::clamp(x - 40, 0.0, 1.0));
  }
  for (int i = 0; i < 6000; ++i) {  // the wall sampled by its area, as a scan at an angle sees it
    const double t = u01(rng);
    c.points.emplace_back(40 + t, uy(rng), 10 * t);
  }
  write_ply((dir.path / "wall.ply").string(), c);
  const std::string run = kScallop + " run " + kZigzag + " --input cloud=" + (dir.path / "wall.ply").string() +
                          " --no-cache -q -o " + (dir.path / "out").string();
  std::string out;
  EXPECT_EQ(test::run_command(run, &out), 0) << out;
  EXPECT_NE(out.find("warning: node 'simulate' (post.simulate) on part 'wall': not reachable by this ball beside what "
                     "was not machined: "),
            std::string::npos) << out;
  const auto report = nlohmann::json::parse(test::read_file(dir.path / "out" / "report.json"));
  EXPECT_TRUE(report["pass"].get<bool>()) << report.dump();
  EXPECT_GT(report["left_out_min_clearance"].get<double>(), 0) << report.dump();  // no move into the wall
  EXPECT_NEAR(report["beside_left_out"]["min"][0].get<double>(), 40 - 4, 0.5);
  // every ball over the part keeps off the exact floor and wall (the ball's radius 4, e 0.01)
  const auto path = nlohmann::json::parse(test::read_file(dir.path / "out" / "toolpath.json"));
  auto to_profile = [](double x, double z) {  // distance in xz to the floor, the wall and its top
    const Eigen::Vector2d q(x, z), profile[4] = {{-100, 0}, {40, 0}, {41, 10}, {200, 10}};
    double d = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector2d a = profile[k], ab = profile[k + 1] - a;
      d = std::min(d, (q - a - std::clamp((q - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) * ab).norm());
    }
    return d;
  };
  int balls = 0;
  for (const auto& pass : path["passes"])
    for (const auto& p : pass) {
      const Eigen::Vector3d centre = Eigen::Vector3d(p["contact"][0], p["contact"][1], p["contact"][2]) +
                                     4.0 * Eigen::Vector3d(p["normal"][0], p["normal"][1], p["normal"][2]);
      if (centre.y() < 0 || centre.y() > 30) continue;
      ++balls;
      EXPECT_GE(to_profile(centre.x(), centre.z()), 4 - 0.01) << centre.transpose();
    }
  EXPECT_GT(balls, 1000);
  // Kept whole (max_slope 90) it is still refused: the planner says where no ball reaches, and the
  // guard where the ball would reach beyond the patch's outline.
  EXPECT_EQ(test::run_command(run + " --set max_slope=90", &out), 1) << out;
  EXPECT_NE(out.find("strips between passes leave more than the scallop limit at every side step tried (uncut "
                     "places, which neither pass's ball reaches, one near x "),
            std::string::npos) << out;
  EXPECT_NE(out.find("beyond the patch's outline, where the surface is only extrapolated from the cloud's points: a "
                     "region left out beside the patch rises there"),
            std::string::npos) << out;
}

TEST(Cli, AFailingNodeNamesTheSetThatGaveItsParameters) {
  // a 20 mm part and a 30 mm ball, the radius from the command line: the error says so
  test::TempDir dir;
  write_wavy(dir.path / "part.xyz", 20, 30);
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kZigzag + " --input cloud=" + (dir.path / "part.xyz").string() +
                                  " --set tool_radius=15 --no-cache -q -o " + (dir.path / "out").string(), &out), 1)
      << out;
  EXPECT_NE(out.find("error: node 'plan' (path.isoparametric) failed on part 'part': the part is 20 mm wide, smaller "
                     "than the 30 mm ball (tool_radius 15 mm): use a smaller tool (given --set tool_radius=15)\n"),
            std::string::npos) << out;
  // refused before running: the --set is named first
  EXPECT_EQ(test::run_command(kScallop + " validate " + kZigzag + " --set scallop_height=-1", &out), 2) << out;
  EXPECT_NE(out.find("error: --set scallop_height=-1 (nodes[12].params.scallop_height): node 'plan': parameter "
                     "'scallop_height' = -1 is out of range; expected 1e-06 .. 100 mm\n"),
            std::string::npos) << out;
}

TEST(Cli, AOneDimensionalCloudIsNamedSo) {
  // a line with micron jitter got fold-over advice
  test::TempDir dir;
  std::string xyz;
  std::uint32_t r = 1;
  auto jitter = [&] {
    r = r * 1664525u + 1013904223u;
    return 0.002 * (static_cast<double>(r >> 8) / (1u << 24) - 0.5);
  };
  char buf[96];
  for (int i = 0; i < 3000; ++i) {
    const double x = 50.0 * i / 2999, y = jitter(), z = jitter();
    std::snprintf(buf, sizeof buf, "%.9g %.9g %.9g\n", x, y, z);
    xyz += buf;
  }
  test::write_file(dir.path / "line.xyz", xyz);
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " run " + kZigzag + " --input cloud=" + (dir.path / "line.xyz").string() +
                                  " --no-cache -q -o " + (dir.path / "out").string(), &out), 1) << out;
  // (the first node that looks at its shape, cloud.trim_steep, says so; it "trimmed 89 % as steep")
  const std::string said = "error: node 'trim' (cloud.trim_steep) failed on part 'line': the cloud is "
                           "one-dimensional: its points lie along a line 50 mm long and ";
  ASSERT_NE(out.find(said), std::string::npos) << out;
  EXPECT_NE(out.find(" mm apart), not on a surface; scallop machines surface patches\n", out.find(said)),
            std::string::npos) << out;
  EXPECT_EQ(out.find("fold"), std::string::npos) << out;
}

TEST(Cli, AWriteNodeCannotWriteOutsideTheOutputFolder) {
  test::TempDir dir;
  write_patch(dir.path / "patch.ply");
  auto graph = [&](const std::string& path) {
    return R"({"scallop_graph": 1, "inputs": {"cloud": {"type": "File"}},
      "nodes": [{"id": "read", "type": "io.read_cloud", "inputs": {"file": "@cloud"}},
                {"id": "save", "type": "io.write_cloud", "params": {"path": ")" + path + R"("},
                 "inputs": {"cloud": "read.cloud"}}]})";
  };
  test::write_file(dir.path / "escape.json", graph("../escaped.ply"));
  test::write_file(dir.path / "inside.json", graph("clouds/copy.ply"));
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " validate " + (dir.path / "escape.json").string(), &out), 2) << out;
  EXPECT_NE(out.find("error: nodes[1].params.path: node 'save': parameter 'path': '../escaped.ply' would be written "
                     "outside the output folder; expected a relative path inside it, without '..'\n"),
            std::string::npos) << out;
  const std::string input = " --input cloud=" + (dir.path / "patch.ply").string() + " --no-cache -q -o ";
  EXPECT_EQ(test::run_command(kScallop + " run " + (dir.path / "escape.json").string() + input +
                                  (dir.path / "out").string(), &out), 2) << out;
  EXPECT_EQ(test::run_command(kScallop + " run " + (dir.path / "escape.json").string() + input +
                                  (dir.path / "out").string() + " --set save.path=/tmp/abs.ply", &out), 2) << out;
  EXPECT_NE(out.find("error: --set save.path=/tmp/abs.ply: node 'save': parameter 'path': '/tmp/abs.ply' is absolute: "
                     "it would be written outside the output folder; expected a relative path inside it, without "
                     "'..'\n"),
            std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir.path / "escaped.ply"));
  // a relative path is written inside -o
  EXPECT_EQ(test::run_command(kScallop + " run " + (dir.path / "inside.json").string() + input +
                                  (dir.path / "out").string(), &out), 0) << out;
  EXPECT_TRUE(fs::exists(dir.path / "out" / "clouds" / "copy.ply"));
}

TEST(Cli, AGraphStringOfAnotherTypeNamesItsPath) {
  test::TempDir dir;
  test::write_file(dir.path / "g.json", R"({"scallop_graph": 1, "params": {"h": {"value": 0.01, "unit": 5}}, "nodes": []})");
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " validate " + (dir.path / "g.json").string(), &out), 2) << out;
  EXPECT_EQ(out, "error: params.h.unit: must be a string, got a number\n1 error(s) in " + (dir.path / "g.json").string() +
                     "\n");
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
