// Graph files: parsing, --set overrides, whole-graph validation, and the execution plan.
//
// A graph file is JSON:
//   { "scallop_graph": 1, "name": "...", "description": "...",
//     "params":  { "tool_radius": { "value": 4, "unit": "mm", "description": "..." }, ... },
//     "inputs":  { "cloud": { "type": "File", "description": "...", "default": "path" } },
//     "nodes":   [ { "id": "knn", "type": "cloud.knn", "params": { "k": 12 },
//                    "inputs": { "cloud": "clean.cloud" } }, ... ],
//     "outputs": { "gcode": "gcode.gcode" } }
// A node input is "<node id>.<output port>" or "@<graph input>"; a parameter value "$name" refers
// to a graph parameter. Validation collects every error before anything runs.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/node.h"

namespace scallop {

inline constexpr int kGraphFormat = 1;
// Objects and arrays nest at most this deep in a graph file (a graph needs 5); a deeper file is
// refused before it is parsed, naming the line and column where it goes too deep.
inline constexpr int kMaxGraphNesting = 64;

// All validation errors of a graph, one line each (JSON path, node id, what was expected).
struct ValidationError : std::runtime_error {
  explicit ValidationError(std::vector<std::string> errs);
  std::vector<std::string> errors;
};

struct GraphParam {
  nlohmann::json value;
  std::string unit, description;
};

struct GraphInput {
  std::string type = "File";
  std::string description;
  std::string default_path;  // relative to the graph file's folder; "" for none
};

struct GraphNode {
  std::string id, type;
  nlohmann::json params = nlohmann::json::object();
  std::vector<std::pair<std::string, std::string>> inputs;  // port -> source text
};

struct Graph {
  std::string path;  // file it came from ("" if from text)
  std::string name, description;
  int format = 0;
  std::map<std::string, GraphParam> params;
  std::map<std::string, GraphInput> inputs;
  std::vector<GraphNode> nodes;
  std::vector<std::pair<std::string, std::string>> outputs;  // name -> source text
  std::vector<std::string> errors;  // structural errors found while parsing
};

// Parses graph JSON; structural problems are kept in Graph::errors (reported by compile()).
// JSON syntax errors throw ValidationError at once.
Graph parse_graph(const std::string& text, const std::string& path_for_messages = "");
Graph load_graph(const std::string& path);

// Where a node input or graph output comes from.
struct Source {
  int node = -1;            // producing node index, or -1 for a graph input
  std::string port;         // output port of that node, or the graph input's name
};

struct PlanNode {
  std::string id;
  const NodeDecl* decl = nullptr;
  nlohmann::json params;                                  // resolved, defaults filled, canonical
  std::vector<std::pair<std::string, Source>> inputs;     // connected ports, in declaration order
  std::vector<int> deps;                                  // producing nodes (unique)
  std::vector<int> dependents;                            // consuming nodes (unique)
  std::map<std::string, std::string> set_by;              // parameter -> the "--set NAME=VALUE" that gave it
};

struct Plan {
  std::string graph_name;
  std::string graph_path;
  std::vector<PlanNode> nodes;
  std::vector<int> order;  // a topological order
  std::vector<std::pair<std::string, Source>> outputs;
  std::map<std::string, GraphInput> inputs;
  nlohmann::json graph_params;  // name -> resolved value
};

struct CompileOptions {
  std::vector<std::string> sets;           // "--set NAME=VALUE" items
  std::set<std::string> provided_inputs;   // graph inputs the caller gives (others: their defaults)
  bool require_inputs = true;              // false for `scallop validate`
};

// Validates the whole graph (collecting every error) and builds the plan; throws ValidationError.
Plan compile(const Graph& graph, const Registry& registry, const CompileOptions& options = {});

// Graphviz text of a graph.
std::string to_dot(const Plan& plan);

}  // namespace scallop
