// Parameters bound to the members of an algorithm's options struct (NodeDecl::options): the
// struct's defaults are the declared ones, validation is that of any parameter, and
// ctx.options<T>() fills every bound member.
#include <gtest/gtest.h>

#include "engine/graph.h"
#include "engine/node.h"
#include "tests/test_support.h"

namespace scallop {
namespace {

struct ScaleOptions {
  int times = 3;
  std::size_t budget = 5000;
  double factor = 0.5;
  bool loud = false;
  std::string label = "x";
  std::string mode = "fast";
  double not_a_parameter = 7;  // set by the node itself
};

NodeDecl scale_node() {
  NodeDecl d;
  d.type = "test.scale";
  d.description = "multiplies its input";
  d.input("a", "Number", "").output("out", "Number", "");
  d.param_float("plain", 2.0, 0, 10, "", "a parameter that is no member");
  d.options<ScaleOptions>()
      .integer("times", &ScaleOptions::times, 1, 10, "", "how often")
      .integer("budget", &ScaleOptions::budget, 1, 1e6, "", "work budget")
      .number("factor", &ScaleOptions::factor, 0, 1, "mm", "the factor")
      .flag("loud", &ScaleOptions::loud, "say more")
      .text("label", &ScaleOptions::label, "a name")
      .choice("mode", &ScaleOptions::mode, {"fast", "exact"}, "how");
  d.run = [](NodeContext& ctx) {
    const ScaleOptions o = ctx.options<ScaleOptions>();
    ctx.set("out", test::Number(ctx.input<test::Number>("a")->value * o.times * o.factor));
  };
  return d;
}

TEST(OptionsBinding, TheDeclaredDefaultIsTheStructsDefault) {
  const NodeDecl d = scale_node();
  const ScaleOptions def;
  EXPECT_EQ(d.find_param("times")->default_value, def.times);
  EXPECT_EQ(d.find_param("budget")->default_value, def.budget);
  EXPECT_EQ(d.find_param("factor")->default_value, def.factor);
  EXPECT_EQ(d.find_param("loud")->default_value, def.loud);
  EXPECT_EQ(d.find_param("label")->default_value, def.label);
  EXPECT_EQ(d.find_param("mode")->default_value, def.mode);
  // the rest of the declaration is as written, in the order written, plain parameters included
  std::vector<std::string> names;
  for (const ParamDecl& p : d.params) names.push_back(p.name);
  EXPECT_EQ(names, (std::vector<std::string>{"plain", "times", "budget", "factor", "loud", "label", "mode"}));
  const ParamDecl& times = *d.find_param("times");
  EXPECT_EQ(times.kind, ParamKind::Int);
  EXPECT_EQ(times.min, 1);
  EXPECT_EQ(times.max, 10);
  EXPECT_EQ(times.description, "how often");
  EXPECT_EQ(d.find_param("factor")->unit, "mm");
  EXPECT_EQ(d.find_param("mode")->kind, ParamKind::Choice);
  EXPECT_EQ(d.find_param("mode")->choices, (std::vector<std::string>{"fast", "exact"}));
}

TEST(OptionsBinding, FillsEveryBoundMemberFromTheParameters) {
  const NodeDecl d = scale_node();
  nlohmann::json params = {{"plain", 2.0}, {"times", 4},    {"budget", 123},   {"factor", 0.25},
                           {"loud", true}, {"label", "y"}, {"mode", "exact"}};
  NodeContext ctx(d, "n", "part", params, {}, nullptr);
  const ScaleOptions o = ctx.options<ScaleOptions>();
  EXPECT_EQ(o.times, 4);
  EXPECT_EQ(o.budget, 123u);
  EXPECT_EQ(o.factor, 0.25);
  EXPECT_TRUE(o.loud);
  EXPECT_EQ(o.label, "y");
  EXPECT_EQ(o.mode, "exact");
  EXPECT_EQ(o.not_a_parameter, 7);  // not bound: the struct's default
  // another struct than the bound one is a programming error
  EXPECT_EQ(test::error_of([&] { ctx.options<test::Number>(); }),
            "node type 'test.scale' binds no parameters to the options struct asked for");
}

TEST(OptionsBinding, DefaultsRunThroughTheEngine) {
  Registry reg = test::make_test_registry();
  reg.add(scale_node());
  const char* text = R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const", "params": {"value": 8}},
      {"id": "s", "type": "test.scale", "inputs": {"a": "a.out"}}]})";
  Plan plan = compile(parse_graph(text), reg);
  EXPECT_EQ(plan.nodes[1].params["times"], 3);
  EXPECT_EQ(plan.nodes[1].params["mode"], "fast");
  auto out = test::run_node(*reg.find("test.scale"), {}, {{"a", std::make_shared<test::Number>(8)}});
  EXPECT_EQ(std::dynamic_pointer_cast<const test::Number>(out.at("out"))->value, 8 * 3 * 0.5);
}

TEST(OptionsBinding, AnOutOfRangeValueIsRefusedWithTheUsualMessage) {
  Registry reg = test::make_test_registry();
  reg.add(scale_node());
  const char* text = R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const"},
      {"id": "s", "type": "test.scale", "params": {"times": 11, "factor": 1.5, "mode": "slow"},
       "inputs": {"a": "a.out"}}]})";
  std::vector<std::string> errors;
  try {
    compile(parse_graph(text), reg);
  } catch (const ValidationError& e) {
    errors = e.errors;
  }
  EXPECT_EQ(errors, (std::vector<std::string>{
                        "nodes[1].params.factor: node 's': parameter 'factor' = 1.5 is out of range; expected 0 .. 1 mm",
                        "nodes[1].params.mode: node 's': parameter 'mode' must be one of fast, exact; got \"slow\"",
                        "nodes[1].params.times: node 's': parameter 'times' = 11 is out of range; expected 1 .. 10"}));
}

struct NarrowOptions {
  std::int8_t small = 1;
  int k = 64;
  std::string how = "b";
};

TEST(OptionsBinding, RefusesADeclarationItsStructCannotHold) {
  // a range the member's type cannot hold
  NodeDecl d;
  d.type = "test.narrow";
  EXPECT_EQ(test::error_of([&] { d.options<NarrowOptions>().integer("small", &NarrowOptions::small, 0, 1000, "", ""); }),
            "node type 'test.narrow': parameter 'small': its range does not fit the type of the member it is bound to");
  // a second options struct
  EXPECT_EQ(test::error_of([&] { d.options<ScaleOptions>(); }),
            "node type 'test.narrow' binds its parameters to a second options struct");
}

TEST(OptionsBinding, TheRegistryRefusesADefaultOutsideItsOwnDeclaration) {
  // the struct's default must be a value the parameter accepts: k = 64 declared 0 .. 10
  Registry reg = test::make_test_registry();
  NodeDecl d;
  d.type = "test.drift";
  d.output("out", "Number", "");
  d.options<NarrowOptions>().integer("k", &NarrowOptions::k, 0, 10, "", "");
  EXPECT_EQ(test::error_of([&] { reg.add(d); }),
            "node type 'test.drift': parameter 'k': its default 64 is out of its range 0 .. 10");
  NodeDecl c;
  c.type = "test.drift";
  c.output("out", "Number", "");
  c.options<NarrowOptions>().choice("how", &NarrowOptions::how, {"a", "c"}, "");
  EXPECT_EQ(test::error_of([&] { reg.add(c); }),
            "node type 'test.drift': parameter 'how': its default \"b\" is not one of its choices");
  EXPECT_EQ(reg.find("test.drift"), nullptr);
}

}  // namespace
}  // namespace scallop
