// Shared helpers for the tests: temp folders and a small registry of test-only nodes.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "engine/node.h"

namespace scallop::test {

// A fresh empty folder under the system temp dir, removed when the object dies.
struct TempDir {
  TempDir();
  ~TempDir();
  std::filesystem::path path;
  std::string str() const { return path.string(); }
};

// A number value for engine tests.
struct Number final : Value {
  double value = 0;
  explicit Number(double v = 0) : value(v) {}
  std::string type_name() const override { return "Number"; }
  void serialize(std::ostream& out) const override;
  static ValuePtr deserialize(std::istream& in);
};

// How often each test node id ran (reset with executions().clear()).
std::map<std::string, int>& executions();

// Test nodes: test.const (param value -> out), test.add (a + b -> out), test.fail (throws),
// test.barrier (in -> out; waits until `parties` barrier nodes are running at once, or fails after 20 s).
Registry make_test_registry();

// Runs a node declaration outside the engine, with its default parameters overridden by
// `params`; `last_progress`, when given, receives the last progress message.
std::map<std::string, ValuePtr> run_node(const NodeDecl& decl, const nlohmann::json& params,
                                         std::map<std::string, ValuePtr> inputs,
                                         std::string* last_progress = nullptr,
                                         std::vector<std::string>* warnings = nullptr);

// The message of the exception of type E `f` throws ("" when it throws none); by default a
// std::logic_error: a declaration the registry refuses, a programming error.
template <class E = std::logic_error, class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  }
  return "";
}

// Writes text to a file.
void write_file(const std::filesystem::path& path, const std::string& text);
std::string read_file(const std::filesystem::path& path);

// Runs a shell command; returns its exit status and fills output with stdout+stderr.
int run_command(const std::string& command, std::string* output = nullptr);

}  // namespace scallop::test
