// Whole-graph validation: every error is collected and each message has an exact text.
#include "engine/graph.h"

#include <gtest/gtest.h>

#include "tests/test_support.h"

namespace scallop {
namespace {

std::vector<std::string> errors_of(const std::string& text, CompileOptions opt = {}) {
  Registry reg = test::make_test_registry();
  try {
    compile(parse_graph(text), reg, opt);
  } catch (const ValidationError& e) {
    return e.errors;
  }
  return {};
}

const char* kGood = R"({
  "scallop_graph": 1, "name": "good",
  "params": {"v": {"value": 2, "unit": "mm"}},
  "nodes": [
    {"id": "a", "type": "test.const", "params": {"value": "$v"}},
    {"id": "b", "type": "test.const", "params": {"value": 3}},
    {"id": "sum", "type": "test.add", "inputs": {"a": "a.out", "b": "b.out"}}
  ],
  "outputs": {"total": "sum.out"}
})";

TEST(Graph, GoodGraphCompilesWithDefaultsAndReferences) {
  Registry reg = test::make_test_registry();
  Plan plan = compile(parse_graph(kGood), reg);
  ASSERT_EQ(plan.nodes.size(), 3u);
  EXPECT_EQ(plan.nodes[0].params["value"], 2.0);
  EXPECT_EQ(plan.nodes[2].params["times"], 1);
  EXPECT_EQ(plan.order.back(), 2);
  ASSERT_EQ(plan.outputs.size(), 1u);
}

TEST(Graph, SetOverridesGraphAndNodeParameters) {
  Registry reg = test::make_test_registry();
  CompileOptions opt;
  opt.sets = {"v=7", "sum.times=3"};
  Plan plan = compile(parse_graph(kGood), reg, opt);
  EXPECT_EQ(plan.nodes[0].params["value"], 7.0);
  EXPECT_EQ(plan.nodes[2].params["times"], 3);
}

TEST(Graph, UnknownNodeType) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "k", "type": "test.ad"}]})"),
            std::vector<std::string>{"nodes[0].type: node 'k': unknown node type 'test.ad'; expected a registered "
                                     "type such as 'test.add' (see 'scallop nodes')"});
}

TEST(Graph, UnknownPort) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "inputs": {"a": "a.out", "c": "a.out"}}]})"),
            std::vector<std::string>{
                "nodes[1].inputs.c: node 's': unknown input port 'c'; expected one of: a, b"});
}

TEST(Graph, UnknownOutputPortOfSource) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "inputs": {"a": "a.result"}}]})"),
            std::vector<std::string>{
                "nodes[1].inputs.a: node 's': node 'a' has no output 'result'; expected one of: out"});
}

TEST(Graph, MissingRequiredInput) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "s", "type": "test.add"}]})"),
            std::vector<std::string>{"nodes[0].inputs: node 's': missing required input 'a' (Number)"});
}

TEST(Graph, DoublyConnectedPort) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "inputs": {"a": "a.out", "a": "a.out"}}]})"),
            std::vector<std::string>{"nodes[1].inputs.a: node 's': input port 'a' is connected twice; expected one "
                                     "source per input"});
}

TEST(Graph, TypeMismatch) {
  Registry reg = test::make_test_registry();
  reg.values().add({"Other", "bin", "", nullptr});
  NodeDecl d;
  d.type = "test.other";
  d.output("o", "Other", "");
  d.run = [](NodeContext&) {};
  reg.add(d);
  try {
    compile(parse_graph(R"({"scallop_graph": 1, "nodes": [{"id": "x", "type": "test.other"},
        {"id": "s", "type": "test.add", "inputs": {"a": "x.o"}}]})"),
            reg);
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.errors, std::vector<std::string>{"nodes[1].inputs.a: node 's': type mismatch: 'x.o' is Other; "
                                                 "expected Number"});
  }
}

TEST(Graph, Cycle) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.add", "inputs": {"a": "c.out"}},
      {"id": "b", "type": "test.add", "inputs": {"a": "a.out"}},
      {"id": "c", "type": "test.add", "inputs": {"a": "b.out"}},
      {"id": "free", "type": "test.const"}]})"),
            std::vector<std::string>{"nodes: cycle a -> b -> c -> a; expected an acyclic graph"});
}

TEST(Graph, SelfLoopIsACycle) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.add", "inputs": {"a": "a.out"}}]})"),
            std::vector<std::string>{"nodes: cycle a -> a; expected an acyclic graph"});
}

TEST(Graph, UnknownParameterKey) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const", "params": {"valeu": 1}}]})"),
            std::vector<std::string>{"nodes[0].params.valeu: node 'a': unknown parameter 'valeu'; expected one of: value"});
}

TEST(Graph, WrongParameterType) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const", "params": {"value": "big"}}]})"),
            std::vector<std::string>{"nodes[0].params.value: node 'a': parameter 'value' must be a number; got \"big\""});
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "params": {"times": 1.5}, "inputs": {"a": "a.out"}}]})"),
            std::vector<std::string>{"nodes[1].params.times: node 's': parameter 'times' must be an integer; got 1.5"});
}

TEST(Graph, ValueOutOfRange) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "params": {"times": 0}, "inputs": {"a": "a.out"}}]})"),
            std::vector<std::string>{"nodes[1].params.times: node 's': parameter 'times' = 0 is out of range; expected 1 .. 10"});
}

TEST(Graph, OutOfRangeThroughSetNamesTheOverride) {
  CompileOptions opt;
  opt.sets = {"sum.times=11", "nope=1"};
  EXPECT_EQ(errors_of(kGood, opt),
            (std::vector<std::string>{"--set nope: unknown graph parameter 'nope'; expected one of: v",
                                      "--set sum.times=11: node 'sum': parameter 'times' = 11 is out of range; expected 1 .. 10"}));
}

TEST(Graph, AGraphParameterSetOutOfRangeNamesTheSetNotOnlyTheNode) {
  // was "nodes[1].params.times: node 'sum': ...": the graph file is fine, the command line is not
  const char* text = R"({"scallop_graph": 1, "params": {"t": {"value": 2}},
    "nodes": [{"id": "a", "type": "test.const"},
              {"id": "sum", "type": "test.add", "params": {"times": "$t"}, "inputs": {"a": "a.out"}}]})";
  CompileOptions opt;
  opt.sets = {"t=11"};
  EXPECT_EQ(errors_of(text, opt), std::vector<std::string>{"--set t=11 (nodes[1].params.times): node 'sum': parameter "
                                                           "'times' = 11 is out of range; expected 1 .. 10"});
  // the plan remembers which --set gave a node's parameters, so a node that fails can say so
  Registry reg = test::make_test_registry();
  opt.sets = {"t=3", "a.value=5"};
  Plan plan = compile(parse_graph(text), reg, opt);
  EXPECT_EQ(plan.nodes[0].set_by, (std::map<std::string, std::string>{{"value", "--set a.value=5"}}));
  EXPECT_EQ(plan.nodes[1].set_by, (std::map<std::string, std::string>{{"times", "--set t=3"}}));
}

TEST(Graph, StringMembersOfAnotherTypeNameTheirPath) {
  // was nlohmann's "[json.exception.type_error.302] type must be string, but is number", no path
  const char* text = R"({"scallop_graph": 1, "name": 5, "description": true,
    "params": {"h": {"value": 0.01, "unit": 5, "description": [1, 2]}},
    "inputs": {"cloud": {"type": 3, "description": null, "default": 7}},
    "nodes": []})";
  CompileOptions opt;
  opt.require_inputs = false;
  EXPECT_EQ(errors_of(text, opt), (std::vector<std::string>{"name: must be a string, got a number",
                                                            "description: must be a string, got a boolean",
                                                            "params.h.unit: must be a string, got a number",
                                                            "params.h.description: must be a string, got an array",
                                                            "inputs.cloud.type: must be a string, got a number",
                                                            "inputs.cloud.description: must be a string, got null",
                                                            "inputs.cloud.default: must be a string, got a number"}));
}

TEST(Graph, MissingGraphInput) {
  const char* text = R"({"scallop_graph": 1, "inputs": {"cloud": {"type": "File"}}, "nodes": []})";
  EXPECT_EQ(errors_of(text), std::vector<std::string>{"inputs.cloud: graph input 'cloud' is not given; expected --input cloud=PATH"});
  CompileOptions opt;
  opt.provided_inputs = {"cloud"};
  EXPECT_TRUE(errors_of(text, opt).empty());
}

TEST(Graph, UnknownGraphParameterReference) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "params": {"v": 1}, "nodes": [{"id": "a", "type": "test.const", "params": {"value": "$w"}}]})"),
            std::vector<std::string>{"nodes[0].params.value: node 'a': unknown graph parameter '$w'; expected one of: v"});
}

TEST(Graph, EveryErrorIsCollected) {
  auto errs = errors_of(R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const", "params": {"value": "x", "extra": 1}},
      {"id": "a", "type": "nope.nope"},
      {"id": "s", "type": "test.add", "inputs": {"a": "zz.out"}}],
      "outputs": {"o": "s.bad"}})");
  EXPECT_EQ(errs, (std::vector<std::string>{
                      "nodes[1].id: node 'a': duplicate node id; expected ids to be unique",
                      "nodes[0].params.extra: node 'a': unknown parameter 'extra'; expected one of: value",
                      "nodes[0].params.value: node 'a': parameter 'value' must be a number; got \"x\"",
                      "nodes[1].type: node 'a': unknown node type 'nope.nope'; expected a registered type (see 'scallop nodes')",
                      "nodes[2].inputs.a: node 's': unknown source 'zz.out'; expected '<node id>.<output port>' or '@<graph input>'",
                      "outputs.o: node 's' has no output 'bad'; expected one of: out"}));
}

// A folder given as the graph was read as an empty file ("unexpected end of input").
TEST(Graph, AFolderIsNotAGraphFile) {
  const std::string dir = ::testing::TempDir();
  try {
    load_graph(dir);
    FAIL() << "no error";
  } catch (const ValidationError& e) {
    ASSERT_EQ(e.errors.size(), 1u);
    EXPECT_EQ(e.errors[0], dir + ": is a folder; expected a graph file (.json)");
  }
}

TEST(Graph, FormatVersionAndSyntax) {
  EXPECT_EQ(errors_of(R"({"scallop_graph": 2, "nodes": []})"),
            std::vector<std::string>{"scallop_graph: unsupported format version 2; expected 1"});
  EXPECT_EQ(errors_of(R"({"nodes": []})"),
            std::vector<std::string>{"scallop_graph: missing format version; expected \"scallop_graph\": 1"});
  // a version of the wrong type is not "missing" (issue 11)
  EXPECT_EQ(errors_of(R"({"scallop_graph": "1", "nodes": []})"),
            std::vector<std::string>{"scallop_graph: format version must be an integer; got \"1\", expected 1"});
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1.5, "nodes": []})"),
            std::vector<std::string>{"scallop_graph: format version must be an integer; got 1.5, expected 1"});
  try {
    parse_graph("{\"scallop_graph\": 1,\n \"nodes\": [}", "g.json");
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.errors.size(), 1u);
    EXPECT_EQ(e.errors[0].rfind("g.json: not valid JSON: parse error at line 2, column 12", 0), 0u) << e.errors[0];
  }
}

std::string nested(int depth) { return std::string(depth, '[') + std::string(depth, ']'); }

TEST(Graph, NestingDeeperThan64LevelsIsRefusedBeforeParsingNamingWhere) {
  // the root object is level 1, "params" 2, "x" 3: 61 arrays make 64 levels, the 62nd (column 89) 65
  auto errors_at_depth = [](int arrays, const std::string& path) -> std::vector<std::string> {
    std::string text = "{\"scallop_graph\": 1, \"nodes\": [],\n \"params\": {\"x\": {\"value\": " + nested(arrays) + "}}}";
    try {
      parse_graph(text, path);
    } catch (const ValidationError& e) {
      return e.errors;
    }
    return {};
  };
  EXPECT_EQ(errors_at_depth(61, "g.json"), std::vector<std::string>{});
  EXPECT_EQ(errors_at_depth(62, "g.json"),
            std::vector<std::string>{"g.json: line 2, column 89: objects and arrays nested more than 64 levels deep; "
                                     "expected at most 64"});
  // 100 000 levels in 200 KB: was 4.3 GB and 49 s before bad_alloc
  EXPECT_EQ(errors_at_depth(100000, ""),
            std::vector<std::string>{"graph: line 2, column 89: objects and arrays nested more than 64 levels deep; "
                                     "expected at most 64"});
  // brackets inside strings do not count
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [], "name": ")" + nested(100) + "\\\"" + nested(100) + "\"}"),
            std::vector<std::string>{});
}

TEST(Graph, SetValueNestedTooDeepIsAnError) {
  CompileOptions opt;
  opt.sets = {"v=" + nested(100)};
  EXPECT_EQ(errors_of(kGood, opt), std::vector<std::string>{"--set v: value nested more than 64 levels deep; expected "
                                                            "a number, a string, true or false"});
}

TEST(Graph, OutputNamesMustBePlainFileNames) {
  // each is written as <-o folder>/<name>.<extension>: these would land outside it
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"}],
      "outputs": {"../../escape": "a.out", "/abs/path": "a.out", "..": "a.out", "a\\b": "a.out", "": "a.out",
                  "new\nline": "a.out", "ok.value-1": "a.out"}})"),
            (std::vector<std::string>{
                "outputs.: output name '' is not a plain file name; expected one without '/', '\\' or control "
                "characters, not '.' or '..'",
                "outputs...: output name '..' is not a plain file name; expected one without '/', '\\' or control "
                "characters, not '.' or '..'",
                "outputs.../../escape: output name '../../escape' is not a plain file name; expected one without '/', "
                "'\\' or control characters, not '.' or '..'",
                "outputs./abs/path: output name '/abs/path' is not a plain file name; expected one without '/', '\\' "
                "or control characters, not '.' or '..'",
                "outputs.a\\b: output name 'a\\b' is not a plain file name; expected one without '/', '\\' or control "
                "characters, not '.' or '..'",
                "outputs.new\\x0aline: output name 'new\\x0aline' is not a plain file name; expected one without '/', "
                "'\\' or control characters, not '.' or '..'"}));
}

TEST(Graph, DefaultInputOutsideTheGraphsFolderIsRefusedUnlessGivenExplicitly) {
  test::TempDir dir;
  const auto folder = dir.path / "graphs";
  test::write_file(dir.path / "secret.ply", "not yours");
  test::write_file(folder / "inside.ply", "yours");
  std::filesystem::create_directories(folder / "data");
  std::filesystem::create_symlink(dir.path / "secret.ply", folder / "data" / "link.ply");
  test::write_file(folder / "g.json", R"({"scallop_graph": 1, "nodes": [],
      "inputs": {"up": {"type": "File", "default": "../secret.ply"},
                 "abs": {"type": "File", "default": ")" + (dir.path / "secret.ply").string() + R"("},
                 "link": {"type": "File", "default": "data/link.ply"},
                 "round": {"type": "File", "default": "data/../../graphs/inside.ply"},
                 "here": {"type": "File", "default": "inside.ply"},
                 "absolute_inside": {"type": "File", "default": ")" + (folder / "inside.ply").string() + R"("}}})");
  Registry reg = test::make_test_registry();
  Graph g = load_graph((folder / "g.json").string());
  const std::string where = std::filesystem::weakly_canonical(folder).string();
  auto refused = [&](const std::string& name, const std::string& path) {
    return "inputs." + name + ".default: default file '" + path + "' lies outside the graph's folder '" + where +
           "'; expected a file inside it, or one given with --input " + name + "=PATH";
  };
  try {
    compile(g, reg);
    FAIL() << "compiled";
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.errors, (std::vector<std::string>{refused("abs", (dir.path / "secret.ply").string()),
                                                  refused("link", "data/link.ply"), refused("up", "../secret.ply")}));
  }
  // given on the command line, any file is the user's choice
  CompileOptions opt;
  opt.provided_inputs = {"up", "abs", "link"};
  EXPECT_NO_THROW(compile(g, reg, opt));
}

TEST(Graph, ListsOfExpectedNamesAreCutAfterTwenty) {
  std::string params;
  for (int i = 0; i < 25; ++i) params += std::string(i ? ", " : "") + "\"p" + std::to_string(100 + i) + "\": 1";
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "params": {)" + params +
                      R"(}, "nodes": [{"id": "a", "type": "test.const", "params": {"value": "$w"}}]})"),
            std::vector<std::string>{"nodes[0].params.value: node 'a': unknown graph parameter '$w'; expected one of: "
                                     "p100, p101, p102, p103, p104, p105, p106, p107, p108, p109, p110, p111, p112, "
                                     "p113, p114, p115, p116, p117, p118, p119, … (5 more)"});
}

// Found while writing fuzz/fuzz_graph (issue 11): a repeated key was told apart by its path's text, so a
// top-level key reading "nodes[-1]" indexed nodes[-1] (a crash) and "nodes[x]" threw std::stoi's
// exception; and one reading "nodes[0].inputs.a" was reported as a port connected twice.
TEST(Graph, RepeatedKeysThatReadLikeNodePathsArePlainDuplicates) {
  const std::string expected =
      "; expected one of: description, inputs, name, nodes, outputs, params, scallop_graph";
  for (const std::string key : {"nodes[-1]", "nodes[x]", "nodes[99999999999]", "nodes[0].inputs.a"})
    EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"}], ")" + key +
                        R"(": 1, ")" + key + R"(": 2})"),
              (std::vector<std::string>{key + ": unknown key '" + key + "'" + expected,
                                        key + ": duplicate key; expected each key once"}))
        << key;
  // a repeated "nodes" keeps the last array, shorter than the one the repeated port is in
  EXPECT_EQ(errors_of(R"({"scallop_graph": 1, "nodes": [{"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.add", "inputs": {"a": "a.out", "a": "a.out"}}], "nodes": []})"),
            (std::vector<std::string>{
                "nodes[1].inputs.a: node '': input port 'a' is connected twice; expected one source per input",
                "nodes: duplicate key; expected each key once"}));
}

// Found by fuzz/fuzz_graph (issue 11): a number too large for a double escaped parse_graph as
// nlohmann's out_of_range ("error: [json.exception.out_of_range.406] …", no file name).
TEST(Graph, NumberTooLargeIsInvalidJson) {
  try {
    parse_graph(R"({"scallop_graph": 1, "params": {"r": 1e999}, "nodes": []})", "g.json");
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.errors, std::vector<std::string>{"g.json: not valid JSON: number overflow parsing '1e999'"});
  }
}

TEST(Graph, DotNamesEveryNodeAndEdge) {
  Registry reg = test::make_test_registry();
  std::string dot = to_dot(compile(parse_graph(kGood), reg));
  EXPECT_NE(dot.find("\"a\" -> \"sum\""), std::string::npos);
  EXPECT_NE(dot.find("\"sum\" -> \"out:total\""), std::string::npos);
}

}  // namespace
}  // namespace scallop
