// Node declarations: the one place a node type is described.
//
// A NodeDecl names the type ("cloud.knn"), its integer version (bump it whenever the output for
// the same inputs and parameters changes: the cache keys on it), a one-line description, its input
// and output ports with value types, and its parameters with type, default, range, unit and
// description. `scallop nodes`, validation and the README reference are all generated from it.
// A parameter that sets a member of the options struct of the node's algorithm is bound to that
// member (NodeDecl::options, OptionsBinding below): its default is the member's, so the two
// cannot drift apart.
#pragma once

#include <concepts>
#include <functional>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <typeindex>
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
template <class Options>
class OptionsBinding;

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

  // Parameters bound to the members of Options, the options struct of the node's algorithm
  // (see OptionsBinding); in run, ctx.options<Options>() fills them. One struct per node.
  template <class Options>
  OptionsBinding<Options> options();
  // What options() records: the bound struct, and per bound parameter how it sets its member
  // (called with the struct as void*, which is an Options).
  std::type_index options_type = typeid(void);
  std::vector<std::function<void(const NodeContext&, void*)>> option_setters;

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
  // The options struct the node's parameters are bound to (NodeDecl::options): Options{} with
  // every bound member set from the node's parameters; the other members keep their defaults.
  // Throws std::logic_error when the declaration binds no parameter to Options.
  template <class Options>
  Options options() const {
    if (decl_.options_type != typeid(Options))
      throw std::logic_error("node type '" + decl_.type + "' binds no parameters to the options struct asked for");
    Options o{};
    for (const auto& set : decl_.option_setters) set(*this, &o);
    return o;
  }

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
  // Adds a node type. Throws std::logic_error when the type is registered already, when a
  // port's value type is not (value types are registered before the nodes that use them), or
  // when a parameter's default is not a value the parameter accepts (out of its range, not one
  // of its choices: a bound options struct's default that drifted from the declaration).
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

// Declares parameters bound to members of Options, the options struct of a node's algorithm:
//   d.options<DenoiseOptions>()
//       .integer("k", &DenoiseOptions::k, 0, 512, "", "neighbours in each fit ...")
//       .flag("normals", &DenoiseOptions::set_normals, "set normals from the fitted quadrics ...");
// and in run: DenoiseOptions o = ctx.options<DenoiseOptions>();
// A bound parameter's default is its member's value in Options{}: the struct is the one home of
// the default. Range, unit, description and choices are declared here, as with param_int & co.,
// and the result is an ordinary ParamDecl (validation, `scallop nodes`, the README reference and
// the cache keys see no difference). Bound and plain parameters may be declared in any order.
template <class Options>
class OptionsBinding {
 public:
  explicit OptionsBinding(NodeDecl& decl) : decl_(decl) {}

  template <std::integral M>
    requires(!std::same_as<M, bool>)
  OptionsBinding& integer(std::string name, M Options::*member, double min, double max, std::string unit,
                          std::string description) {
    if (min < static_cast<double>(std::numeric_limits<M>::lowest()) ||
        max > static_cast<double>(std::numeric_limits<M>::max()))
      throw std::logic_error("node type '" + decl_.type + "': parameter '" + name +
                             "': its range does not fit the type of the member it is bound to");
    decl_.param_int(name, static_cast<long long>(Options{}.*member), min, max, std::move(unit),
                    std::move(description));
    return bind(std::move(name), [member](const NodeContext& ctx, const std::string& n, Options& o) {
      o.*member = static_cast<M>(ctx.integer(n));
    });
  }
  OptionsBinding& number(std::string name, double Options::*member, double min, double max, std::string unit,
                         std::string description) {
    decl_.param_float(name, Options{}.*member, min, max, std::move(unit), std::move(description));
    return bind(std::move(name),
                [member](const NodeContext& ctx, const std::string& n, Options& o) { o.*member = ctx.number(n); });
  }
  OptionsBinding& flag(std::string name, bool Options::*member, std::string description) {
    decl_.param_bool(name, Options{}.*member, std::move(description));
    return bind(std::move(name),
                [member](const NodeContext& ctx, const std::string& n, Options& o) { o.*member = ctx.flag(n); });
  }
  OptionsBinding& text(std::string name, std::string Options::*member, std::string description) {
    decl_.param_string(name, Options{}.*member, std::move(description));
    return bind(std::move(name),
                [member](const NodeContext& ctx, const std::string& n, Options& o) { o.*member = ctx.text(n); });
  }
  OptionsBinding& choice(std::string name, std::string Options::*member, std::vector<std::string> choices,
                         std::string description) {
    decl_.param_choice(name, Options{}.*member, std::move(choices), std::move(description));
    return bind(std::move(name),
                [member](const NodeContext& ctx, const std::string& n, Options& o) { o.*member = ctx.text(n); });
  }

 private:
  template <class Set>
  OptionsBinding& bind(std::string name, Set set) {
    decl_.option_setters.push_back([name = std::move(name), set](const NodeContext& ctx, void* o) {
      set(ctx, name, *static_cast<Options*>(o));
    });
    return *this;
  }
  NodeDecl& decl_;
};

template <class Options>
OptionsBinding<Options> NodeDecl::options() {
  if (options_type != typeid(void) && options_type != typeid(Options))
    throw std::logic_error("node type '" + type + "' binds its parameters to a second options struct");
  options_type = typeid(Options);
  return OptionsBinding<Options>(*this);
}

// JSON form of a declaration (for `scallop nodes --json` and generated docs).
nlohmann::json to_json(const NodeDecl& decl);
// Human-readable reference of a declaration (Markdown).
std::string to_markdown(const NodeDecl& decl);

}  // namespace scallop
