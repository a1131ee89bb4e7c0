#include "engine/node.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace scallop {

std::string to_string(ParamKind kind) {
  switch (kind) {
    case ParamKind::Int: return "integer";
    case ParamKind::Float: return "number";
    case ParamKind::Bool: return "boolean";
    case ParamKind::String: return "string";
    case ParamKind::Choice: return "choice";
  }
  return "?";
}

NodeDecl& NodeDecl::input(std::string name, std::string type_name, std::string desc, bool required) {
  inputs.push_back({std::move(name), std::move(type_name), required, std::move(desc)});
  return *this;
}
NodeDecl& NodeDecl::output(std::string name, std::string type_name, std::string desc) {
  outputs.push_back({std::move(name), std::move(type_name), true, std::move(desc)});
  return *this;
}
NodeDecl& NodeDecl::param_int(std::string name, long long def, double lo, double hi, std::string unit,
                              std::string desc) {
  params.push_back({std::move(name), ParamKind::Int, def, lo, hi, std::move(unit), std::move(desc), {}});
  return *this;
}
NodeDecl& NodeDecl::param_float(std::string name, std::optional<double> def, double lo, double hi,
                                std::string unit, std::string desc) {
  nlohmann::json d = def ? nlohmann::json(*def) : nlohmann::json();
  params.push_back({std::move(name), ParamKind::Float, d, lo, hi, std::move(unit), std::move(desc), {}});
  return *this;
}
NodeDecl& NodeDecl::param_bool(std::string name, bool def, std::string desc) {
  params.push_back({std::move(name), ParamKind::Bool, def, {}, {}, "", std::move(desc), {}});
  return *this;
}
NodeDecl& NodeDecl::param_string(std::string name, std::string def, std::string desc) {
  params.push_back({std::move(name), ParamKind::String, def, {}, {}, "", std::move(desc), {}});
  return *this;
}
NodeDecl& NodeDecl::param_output_path(std::string name, std::string desc) {
  param_string(std::move(name), "", std::move(desc));
  params.back().output_path = true;
  return *this;
}
NodeDecl& NodeDecl::param_choice(std::string name, std::string def, std::vector<std::string> choices,
                                 std::string desc) {
  params.push_back({std::move(name), ParamKind::Choice, def, {}, {}, "", std::move(desc), std::move(choices)});
  return *this;
}

namespace {
std::string number_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

template <class T>
const T* find_named(const std::vector<T>& v, const std::string& name) {
  for (const auto& x : v)
    if (x.name == name) return &x;
  return nullptr;
}
}  // namespace

const PortDecl* NodeDecl::find_input(const std::string& n) const { return find_named(inputs, n); }
const PortDecl* NodeDecl::find_output(const std::string& n) const { return find_named(outputs, n); }
const ParamDecl* NodeDecl::find_param(const std::string& n) const { return find_named(params, n); }

NodeContext::NodeContext(const NodeDecl& decl, std::string node_id, std::string part, nlohmann::json params,
                         std::map<std::string, ValuePtr> inputs,
                         std::function<void(double, const std::string&)> progress,
                         std::function<void(const std::string&)> warn)
    : decl_(decl),
      node_id_(std::move(node_id)),
      part_(std::move(part)),
      params_(std::move(params)),
      inputs_(std::move(inputs)),
      progress_(std::move(progress)),
      warn_(std::move(warn)) {}

bool NodeContext::has_input(const std::string& port) const {
  auto it = inputs_.find(port);
  return it != inputs_.end() && it->second;
}

ValuePtr NodeContext::raw_input(const std::string& port) const {
  auto it = inputs_.find(port);
  if (it == inputs_.end() || !it->second) throw NodeError("input '" + port + "' is not connected");
  return it->second;
}

namespace {
const nlohmann::json& param_value(const nlohmann::json& params, const std::string& name) {
  auto it = params.find(name);
  if (it == params.end() || it->is_null()) throw NodeError("parameter '" + name + "' has no value");
  return *it;
}
}  // namespace

long long NodeContext::integer(const std::string& name) const { return param_value(params_, name).get<long long>(); }
double NodeContext::number(const std::string& name) const { return param_value(params_, name).get<double>(); }
bool NodeContext::flag(const std::string& name) const { return param_value(params_, name).get<bool>(); }
std::string NodeContext::text(const std::string& name) const { return param_value(params_, name).get<std::string>(); }

void NodeContext::set_output(const std::string& port, ValuePtr value) {
  if (!decl_.find_output(port)) throw std::logic_error("node " + decl_.type + " has no output '" + port + "'");
  outputs_[port] = std::move(value);
}

void NodeContext::progress(double fraction, const std::string& message) const {
  if (progress_) progress_(std::clamp(fraction, 0.0, 1.0), message);
}

void NodeContext::warn(const std::string& message) const {
  if (warn_) warn_(message);
}

namespace {
// Why a parameter's default is not one of the values its declaration accepts ("" when it is).
std::string default_problem(const ParamDecl& p) {
  const nlohmann::json& d = p.default_value;
  if (d.is_null()) return "";  // required: no default
  if (p.kind == ParamKind::Choice && std::find(p.choices.begin(), p.choices.end(), d.get<std::string>()) == p.choices.end())
    return "its default " + d.dump() + " is not one of its choices";
  if ((p.kind == ParamKind::Int || p.kind == ParamKind::Float) &&
      ((p.min && d.get<double>() < *p.min) || (p.max && d.get<double>() > *p.max)))
    return "its default " + d.dump() + " is out of its range " + (p.min ? number_text(*p.min) : "") + " .. " +
           (p.max ? number_text(*p.max) : "");
  return "";
}
}  // namespace

void Registry::add(NodeDecl decl) {
  if (nodes_.count(decl.type)) throw std::logic_error("node type '" + decl.type + "' is registered twice");
  for (const ParamDecl& p : decl.params)
    if (auto problem = default_problem(p); !problem.empty())
      throw std::logic_error("node type '" + decl.type + "': parameter '" + p.name + "': " + problem);
  for (const auto* ports : {&decl.inputs, &decl.outputs})
    for (const PortDecl& p : *ports)
      if (!values_.find(p.type))
        throw std::logic_error("node type '" + decl.type + "': " + (ports == &decl.inputs ? "input" : "output") +
                               " '" + p.name + "' has value type '" + p.type + "', which is not registered");
  std::string type = decl.type;
  nodes_[type] = std::move(decl);
}

void Registry::add_domain(const std::string& domain, std::vector<NodeDecl> decls) {
  for (NodeDecl& d : decls) {
    if (!d.type.starts_with(domain + "."))
      throw std::logic_error("node type '" + d.type + "' is in the domain '" + domain + "': name it '" + domain +
                             ".<name>'");
    add(std::move(d));
  }
}

const NodeDecl* Registry::find(const std::string& type) const {
  auto it = nodes_.find(type);
  return it == nodes_.end() ? nullptr : &it->second;
}

nlohmann::json to_json(const NodeDecl& d) {
  nlohmann::json j;
  j["type"] = d.type;
  j["version"] = d.version;
  j["description"] = d.description;
  auto ports = [](const std::vector<PortDecl>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (const auto& p : v)
      a.push_back({{"name", p.name}, {"type", p.type}, {"required", p.required}, {"description", p.description}});
    return a;
  };
  j["inputs"] = ports(d.inputs);
  j["outputs"] = ports(d.outputs);
  j["params"] = nlohmann::json::array();
  for (const auto& p : d.params) {
    nlohmann::json pj{{"name", p.name}, {"type", to_string(p.kind)}, {"default", p.default_value},
                      {"unit", p.unit}, {"description", p.description}};
    if (p.min) pj["min"] = *p.min;
    if (p.max) pj["max"] = *p.max;
    if (!p.choices.empty()) pj["choices"] = p.choices;
    j["params"].push_back(pj);
  }
  return j;
}

std::string to_markdown(const NodeDecl& d) {
  std::ostringstream s;
  s << "### `" << d.type << "` (version " << d.version << ")\n\n" << d.description << "\n\n";
  auto ports = [&](const char* title, const std::vector<PortDecl>& v) {
    if (v.empty()) return;
    s << "| " << title << " | type | |\n|---|---|---|\n";
    for (const auto& p : v)
      s << "| `" << p.name << "` | " << p.type << (p.required ? "" : " (optional)") << " | " << p.description
        << " |\n";
    s << "\n";
  };
  ports("input", d.inputs);
  ports("output", d.outputs);
  if (!d.params.empty()) {
    s << "| parameter | type | default | range | unit | |\n|---|---|---|---|---|---|\n";
    for (const auto& p : d.params) {
      std::string range;
      if (p.min || p.max) range = (p.min ? number_text(*p.min) : "") + " .. " + (p.max ? number_text(*p.max) : "");
      if (!p.choices.empty()) {
        for (std::size_t i = 0; i < p.choices.size(); ++i) range += (i ? " \\| " : "") + p.choices[i];
      }
      std::string def = p.default_value.is_null() ? "required" : p.default_value.dump();
      s << "| `" << p.name << "` | " << to_string(p.kind) << " | " << def << " | " << range << " | " << p.unit
        << " | " << p.description << " |\n";
    }
    s << "\n";
  }
  return s.str();
}

}  // namespace scallop
