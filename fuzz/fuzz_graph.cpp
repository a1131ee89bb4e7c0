// libFuzzer target: the graph loader, as `scallop validate` uses it: parse_graph (JSON, structure,
// duplicate keys, nesting), then compile against the built-in node registry (types, ports,
// parameters, --set overrides, outputs, default inputs, cycles), then to_dot on a valid plan.
// The input is the graph's text; after a NUL byte, NUL-separated "--set NAME=VALUE" items follow.
// The loader's contract is a Plan or a ValidationError: any other exception escapes and is a bug.
#include <cstddef>
#include <cstdint>
#include <string>

#include "engine/graph.h"
#include "nodes/all_nodes.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string input(reinterpret_cast<const char*>(data), size);
  const std::size_t nul = input.find('\0');
  const std::string text = input.substr(0, nul);
  scallop::CompileOptions options;
  options.require_inputs = false;  // as `scallop validate`: graph inputs need not be given
  for (std::size_t at = nul; at != std::string::npos && at < input.size();) {
    const std::size_t next = input.find('\0', at + 1);
    options.sets.push_back(input.substr(at + 1, next == std::string::npos ? std::string::npos : next - at - 1));
    at = next;
  }
  try {
    const scallop::Graph graph = scallop::parse_graph(text, "fuzz.json");
    const scallop::Plan plan = scallop::compile(graph, scallop::builtin_registry(), options);
    volatile std::size_t n = scallop::to_dot(plan).size();
    (void)n;
  } catch (const scallop::ValidationError&) {
  }
  return 0;
}
