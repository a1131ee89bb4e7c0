// Node declarations: the one place a node type is described.
//
// A NodeDecl names the type ("cloud.knn"), its integer version (bump it whenever the output for
// the same inputs and parameters changes: the cache keys on it), a one-line description, its input
// and output ports with value types, and its parameters with type, default, range, unit and
// description. `scallop nodes`, validation and the README reference are all generated from it.
#pragma once

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "engine/value.h"

namespace scallop {

enum class ParamKind { Int, Float, Bool, String, Choice };
std::string to_string(ParamKind kind);

struct ParamDecl {
  std::string name;
  ParamKind kind = ParamKind::Float;
  nlohmann::json default_value;          // null: the parameter must be given
  std::optional<double> min, max;        // inclusive bounds for Int and Float
  std::string unit;                      // "mm", "" for none
  std::string description;
  std::vector<std::string> choices;      // for Choice
  bool output_path = false;              // String: a file the node writes, relative to the output
                                         // folder; validation refuses one that leaves it
};

struct PortDecl {
  std::string name;
  std::string type;  // value type name
  bool required = true;
  std::string description;
};

class NodeContext;

struct NodeDecl {
  std::string type;
  int version = 1;
  std::string description;
  std::vector<PortDecl> inputs;
  std::vector<PortDecl> outputs;
  std::vector<ParamDecl> params;
  bool cache_on_disk = true;  // cheap nodes need not go to disk
  std::function<void(NodeContext&)> run;

  // Fluent helpers so a declaration reads like a table.
  NodeDecl& input(std::string name, std::string type, std::string description, bool required = true);
  NodeDecl& output(std::string name, std::string type, std::string description);
  NodeDecl& param_int(std::string name, long long def, double min, double max, std::string unit,
                      std::string description);
  NodeDecl& param_float(std::string name, std::optional<double> def, double min, double max,
                        std::string unit, std::string description);
  NodeDecl& param_bool(std::string name, bool def, std::string description);
  NodeDecl& param_string(std::string name, std::string def, std::string description);
  NodeDecl& param_choice(std::string name, std::string def, std::vector<std::string> choices,
                         std::string description);
  // A String naming a file the node writes inside the output folder (engine/output_path.h).
  NodeDecl& param_output_path(std::string name, std::string description);

  const PortDecl* find_input(const std::string& name) const;
  const PortDecl* find_output(const std::string& name) const;
  const ParamDecl* find_param(const std::string& name) const;
};

// Thrown by a node's run function for bad input it detects (empty cloud, no boundary...).
// The executor adds node id, node type and part.
struct NodeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Thrown by a node for an input file it cannot read or that is malformed (a source node's bad
// input, not a failed computation): `scallop run` then exits 2 (bad input), as for a missing file,
// instead of 1.
struct InputError : NodeError {
  using NodeError::NodeError;
};

// What a running node sees: its inputs, its resolved parameters, and where its outputs go.
class NodeContext {
 public:
  NodeContext(const NodeDecl& decl, std::string node_id, std::string part, nlohmann::json params,
              std::map<std::string, ValuePtr> inputs,
              std::function<void(double, const std::string&)> progress,
              std::function<void(const std::string&)> warn = nullptr);

  bool has_input(const std::string& port) const;
  template <class T>
  std::shared_ptr<const T> input(const std::string& port) const {
    auto v = std::dynamic_pointer_cast<const T>(raw_input(port));
    if (!v) throw NodeError("input '" + port + "' has the wrong value type");
    return v;
  }
  ValuePtr raw_input(const std::string& port) const;

  long long integer(const std::string& name) const;
  double number(const std::string& name) const;
  bool flag(const std::string& name) const;
  std::string text(const std::string& name) const;
  const nlohmann::json& params() const { return params_; }

  void set_output(const std::string& port, ValuePtr value);
  template <class T>
  void set(const std::string& port, T&& value) {
    set_output(port, std::make_shared<const std::decay_t<T>>(std::forward<T>(value)));
  }
  // Reports progress of long work in [0, 1]; cheap to call often.
  void progress(double fraction, const std::string& message = {}) const;
  // Says something the user must see even when the node succeeds (one line, no node id: the
  // runner adds it): `scallop` prints "warning: node 'ID' (TYPE) on part 'P': message" on
  // stderr, also with -q, and the events stream gets a node_warning event. Thread-safe when the
  // handler is (the executor's is).
  void warn(const std::string& message) const;

  // The run's output folder ("" : the working directory); files a node writes go inside it
  // (output_file in engine/output_path.h).
  const std::string& output_dir() const { return output_dir_; }
  void set_output_dir(std::string dir) { output_dir_ = std::move(dir); }

  const std::string& node_id() const { return node_id_; }
  const std::string& part() const { return part_; }
  const NodeDecl& decl() const { return decl_; }
  std::map<std::string, ValuePtr> take_outputs() { return std::move(outputs_); }

 private:
  const NodeDecl& decl_;
  std::string node_id_, part_, output_dir_;
  nlohmann::json params_;
  std::map<std::string, ValuePtr> inputs_, outputs_;
  std::function<void(double, const std::string&)> progress_;
  std::function<void(const std::string&)> warn_;
};

// All node types and value types the engine knows.
class Registry {
 public:
  // Adds a node type. Throws std::logic_error when the type is registered already, or when a
  // port's value type is not (value types are registered before the nodes that use them).
  void add(NodeDecl decl);
  // Adds the nodes of one domain, the folder nodes/<domain>/: each type must be named
  // "<domain>.<name>", so that two domains' nodes (mesh.denoise, cloud.denoise) never clash.
  void add_domain(const std::string& domain, std::vector<NodeDecl> decls);
  const NodeDecl* find(const std::string& type) const;
  const std::map<std::string, NodeDecl>& nodes() const { return nodes_; }
  ValueTypes& values() { return values_; }
  const ValueTypes& values() const { return values_; }

 private:
  std::map<std::string, NodeDecl> nodes_;
  ValueTypes values_;
};

// JSON form of a declaration (for `scallop nodes --json` and generated docs).
nlohmann::json to_json(const NodeDecl& decl);
// Human-readable reference of a declaration (Markdown).
std::string to_markdown(const NodeDecl& decl);

}  // namespace scallop
