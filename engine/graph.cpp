#include "engine/graph.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "engine/output_path.h"

namespace scallop {
namespace fs = std::filesystem;

ValidationError::ValidationError(std::vector<std::string> errs)
    : std::runtime_error(errs.empty() ? "invalid graph" : errs.front()), errors(std::move(errs)) {}

namespace {

using json = nlohmann::json;

// A name or value from the graph as messages show it: at most ~kMax bytes (cut at a UTF-8 character
// boundary, "…" marks the cut) and control characters as \xNN. Every message then has a bounded
// length, so a graph's errors take space linear in its size, whatever its names and values.
std::string shown(const std::string& s, std::size_t kMax = 64) {
  std::size_t n = s.size();
  if (n > kMax) {
    n = kMax - 4;
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n;  // a continuation byte
  }
  std::string out;
  for (std::size_t i = 0; i < n; ++i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (c < 0x20 || c == 0x7f) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02x", c);
      out += buf;
    } else {
      out += static_cast<char>(c);
    }
  }
  return n < s.size() ? out + "…" : out;
}

std::string in_quotes(const std::string& s) { return "'" + shown(s) + "'"; }

// A JSON path as messages show it: one longer than 160 bytes keeps its first 40 and last 100,
// "…" between (a path of 64 levels of long keys would otherwise repeat kilobytes per message).
std::string shown_path(const std::string& path) {
  if (path.size() <= 160) return path;
  std::size_t head = 40, tail = path.size() - 100;
  while (head > 0 && (static_cast<unsigned char>(path[head]) & 0xC0) == 0x80) --head;
  while (tail < path.size() && (static_cast<unsigned char>(path[tail]) & 0xC0) == 0x80) ++tail;
  return path.substr(0, head) + "…" + path.substr(tail);
}

// "a, b, c"; more than 20 names end with "… (N more)", so that a message listing what was
// expected stays short however many names the graph has.
template <class Range, class Name>
std::string join_listed(const Range& range, std::size_t size, Name name) {
  constexpr std::size_t kMaxListed = 20;
  std::string s;
  std::size_t i = 0;
  for (auto it = range.begin(); it != range.end() && i < kMaxListed; ++it, ++i) s += (i ? ", " : "") + shown(name(*it));
  if (size > kMaxListed) s += ", … (" + std::to_string(size - kMaxListed) + " more)";
  return s.empty() ? "(none)" : s;
}

std::string join_names(const std::vector<std::string>& names) {
  return join_listed(names, names.size(), [](const std::string& n) -> const std::string& { return n; });
}

// Finds repeated keys (nlohmann keeps only the last) in a second, SAX pass over text that already
// parsed: nlohmann's parser with a callback is quadratic in the members of an object (its
// end_object scans the parent for discarded values; 20 000 graph inputs took 4.7 s). A frame keeps
// its current key or element index; a JSON path is put together only for a duplicate.
class DuplicateKeyFinder : public nlohmann::json_sax<json> {
 public:
  struct Duplicate {
    std::string path;     // JSON path of the repeated key
    std::string key;
    int node = -1;        // for nodes[i].inputs.KEY and nodes[i].params.KEY: i, else -1
    std::string section;  // "inputs" or "params" when node >= 0
  };
  std::vector<Duplicate> duplicates;

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return start(true); }
  bool start_array(std::size_t) override { return start(false); }
  bool end_object() override { return end(); }
  bool end_array() override { return end(); }
  bool key(string_t& k) override {
    auto& f = frames_.back();
    if (!f.keys.insert(k).second) {
      Duplicate d{path_of(frames_.size() - 1, k), k, -1, ""};
      // Told from the frames, not from the path's text: a key may itself read "nodes[-1]".
      if (frames_.size() == 4 && frames_[0].is_object && frames_[0].key == "nodes" && !frames_[1].is_object &&
          frames_[2].is_object && (frames_[2].key == "inputs" || frames_[2].key == "params")) {
        d.node = frames_[1].count;
        d.section = frames_[2].key;
      }
      duplicates.push_back(std::move(d));
    }
    f.key = k;
    return true;
  }
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

 private:
  struct Frame {
    bool is_object;
    std::set<std::string> keys;
    std::string key;
    int count;
  };
  std::vector<Frame> frames_;

  bool value() {
    if (!frames_.empty() && !frames_.back().is_object) ++frames_.back().count;
    return true;
  }
  bool start(bool is_object) {
    frames_.push_back({is_object, {}, "", 0});
    return true;
  }
  bool end() {
    frames_.pop_back();
    return value();
  }

  // "a.b[2].key": the keys and indices of the enclosing frames, then `key`.
  std::string path_of(std::size_t depth, const std::string& key) const {
    std::string path;
    auto add_key = [&](const std::string& k) {
      if (!path.empty()) path += '.';
      path += shown(k);
    };
    for (std::size_t i = 0; i < depth; ++i) {
      if (frames_[i].is_object) {
        add_key(frames_[i].key);
      } else {
        path += '[';
        path += std::to_string(frames_[i].count);
        path += ']';
      }
    }
    add_key(key);
    return shown_path(path);
  }
};

template <class Map>
std::string join_keys(const Map& m) {
  return join_listed(m, m.size(), [](const auto& kv) -> const std::string& { return kv.first; });
}

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j)
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

// An absolute path with symbolic links resolved as far as it exists.
fs::path resolved(const fs::path& p) {
  std::error_code ec;
  fs::path r = fs::weakly_canonical(fs::absolute(p, ec), ec);
  if (ec) r = fs::absolute(p, ec).lexically_normal();
  if (r.has_filename() || r == r.root_path()) return r;
  return r.parent_path();  // "a/b/" -> "a/b"
}

// The folder a graph's relative paths start from: its file's folder, or the working directory for
// a graph given as text; absolute, symbolic links resolved.
fs::path graph_folder(const Graph& graph) {
  return resolved(graph.path.empty() ? fs::path(".") : fs::absolute(graph.path).parent_path());
}

std::string node_prefix(const std::string& path, const std::string& id) {
  return path + ": node " + in_quotes(id) + ": ";
}

// Where JSON text first nests objects and arrays more than `max_depth` deep ("line L, column C"),
// or "" if it never does; brackets inside strings do not count. One pass, no allocation: this runs
// before the parser, whose tree (and the duplicate-key finder's frames) would otherwise grow with
// the depth of whatever file it is given (100 000 levels in 200 KB took 4.3 GB).
std::string too_deep_at(const std::string& text, int max_depth) {
  int depth = 0;
  std::size_t line = 1, line_start = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      line_start = i + 1;
    }
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth)
        return "line " + std::to_string(line) + ", column " + std::to_string(i - line_start + 1);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return "";
}

// The string member `key` of object `j` ("" when absent). Any other type is an error naming its
// JSON path ("params.h.unit: must be a string, got a number"), not nlohmann's pathless
// "type must be string, but is number".
std::string string_member(const json& j, const char* key, const std::string& path, std::vector<std::string>& errs) {
  auto it = j.find(key);
  if (it == j.end()) return "";
  if (it->is_string()) return it->get<std::string>();
  const std::string type = it->type_name();
  const bool vowel = std::string("aeiou").find(type[0]) != std::string::npos;
  errs.push_back(shown_path(path) + ": must be a string, got " + (it->is_null() ? "null" : (vowel ? "an " : "a ") + type));
  return "";
}

}  // namespace

Graph parse_graph(const std::string& text, const std::string& path) {
  Graph g;
  g.path = path;
  if (std::string at = too_deep_at(text, kMaxGraphNesting); !at.empty())
    throw ValidationError({(path.empty() ? std::string("graph") : path) + ": " + at +
                           ": objects and arrays nested more than " + std::to_string(kMaxGraphNesting) +
                           " levels deep; expected at most " + std::to_string(kMaxGraphNesting)});
  json j;
  try {
    j = json::parse(text);
  } catch (const json::exception& e) {
    // A syntax error ("parse error at line 2, column 12: ..."), or a number too large for a double
    // ("number overflow parsing '1e999'", an out_of_range that used to escape as it was): the
    // text after nlohmann's "[json.exception.…] " tag, bounded like the other quoted values.
    std::string what = e.what();
    auto pos = what.find("] ");
    throw ValidationError({(path.empty() ? std::string("graph") : path) + ": not valid JSON: " +
                           shown(pos == std::string::npos ? what : what.substr(pos + 2), 200)});
  }
  DuplicateKeyFinder dups;
  json::sax_parse(text, &dups);
  auto& errs = g.errors;
  if (!j.is_object()) {
    errs.push_back("(root): expected a JSON object");
    return g;
  }
  static const std::set<std::string> top_keys{"scallop_graph", "name", "description", "params",
                                              "inputs", "nodes", "outputs"};
  for (const auto& [k, v] : j.items())
    if (!top_keys.count(k))
      errs.push_back(k + ": unknown key " + in_quotes(k) + "; expected one of: " +
                     join_names({top_keys.begin(), top_keys.end()}));

  if (!j.contains("scallop_graph"))
    errs.push_back("scallop_graph: missing format version; expected \"scallop_graph\": " + std::to_string(kGraphFormat));
  else if (!j["scallop_graph"].is_number_integer())
    errs.push_back("scallop_graph: format version must be an integer; got " + j["scallop_graph"].dump() +
                   ", expected " + std::to_string(kGraphFormat));
  else if ((g.format = j["scallop_graph"].get<int>()) != kGraphFormat)
    errs.push_back("scallop_graph: unsupported format version " + std::to_string(g.format) + "; expected " +
                   std::to_string(kGraphFormat));
  g.name = string_member(j, "name", "name", errs);
  g.description = string_member(j, "description", "description", errs);

  if (j.contains("params")) {
    if (!j["params"].is_object()) errs.push_back("params: expected an object of graph parameters");
    else
      for (const auto& [k, v] : j["params"].items()) {
        GraphParam p;
        if (v.is_object()) {
          if (!v.contains("value")) errs.push_back("params." + shown(k) + ": missing \"value\"");
          p.value = v.value("value", json());
          p.unit = string_member(v, "unit", "params." + shown(k) + ".unit", errs);
          p.description = string_member(v, "description", "params." + shown(k) + ".description", errs);
        } else {
          p.value = v;
        }
        g.params[k] = p;
      }
  }
  if (j.contains("inputs")) {
    if (!j["inputs"].is_object()) errs.push_back("inputs: expected an object of graph inputs");
    else
      for (const auto& [k, v] : j["inputs"].items()) {
        GraphInput in;
        if (v.is_object()) {
          const std::string at = "inputs." + shown(k);
          if (std::string t = string_member(v, "type", at + ".type", errs); v.contains("type") && v["type"].is_string())
            in.type = t;  // a type of another kind is reported by string_member; keep the default
          in.description = string_member(v, "description", at + ".description", errs);
          in.default_path = string_member(v, "default", at + ".default", errs);
        }
        if (in.type != "File") errs.push_back("inputs." + shown(k) + ".type: unsupported graph input type " +
                                              in_quotes(in.type) + "; expected 'File'");
        g.inputs[k] = in;
      }
  }
  if (!j.contains("nodes") || !j["nodes"].is_array()) {
    errs.push_back("nodes: missing; expected an array of nodes");
  } else {
    int i = 0;
    for (const auto& n : j["nodes"]) {
      std::string at = "nodes[" + std::to_string(i++) + "]";
      GraphNode node;
      if (!n.is_object()) {
        errs.push_back(at + ": expected an object with \"id\", \"type\", \"params\", \"inputs\"");
        g.nodes.push_back(node);
        continue;
      }
      if (!n.contains("id") || !n["id"].is_string() || n["id"].get<std::string>().empty())
        errs.push_back(at + ".id: missing node id; expected a non-empty string");
      else
        node.id = n["id"].get<std::string>();
      if (!n.contains("type") || !n["type"].is_string())
        errs.push_back(node_prefix(at + ".type", node.id) + "missing node type; expected a string such as 'cloud.knn'");
      else
        node.type = n["type"].get<std::string>();
      for (const auto& [k, v] : n.items())
        if (k != "id" && k != "type" && k != "params" && k != "inputs" && k != "comment")
          errs.push_back(node_prefix(at + "." + shown(k), node.id) + "unknown key " + in_quotes(k) +
                         "; expected one of: comment, id, inputs, params, type");
      if (n.contains("params")) {
        if (n["params"].is_object()) node.params = n["params"];
        else errs.push_back(node_prefix(at + ".params", node.id) + "expected an object");
      }
      if (n.contains("inputs")) {
        if (!n["inputs"].is_object()) {
          errs.push_back(node_prefix(at + ".inputs", node.id) + "expected an object of port: source");
        } else {
          for (const auto& [port, src] : n["inputs"].items()) {
            if (!src.is_string())
              errs.push_back(node_prefix(at + ".inputs." + shown(port), node.id) +
                             "expected a source string '<node id>.<output port>' or '@<graph input>'");
            else
              node.inputs.emplace_back(port, src.get<std::string>());
          }
        }
      }
      g.nodes.push_back(node);
    }
  }
  if (j.contains("outputs")) {
    if (!j["outputs"].is_object()) errs.push_back("outputs: expected an object of name: source");
    else
      for (const auto& [k, v] : j["outputs"].items()) {
        if (!v.is_string()) errs.push_back("outputs." + shown(k) + ": expected a source string '<node id>.<output port>'");
        else g.outputs.emplace_back(k, v.get<std::string>());
      }
  }
  for (const auto& d : dups.duplicates) {
    // nodes[i].inputs.port repeated: the port is connected twice. (A repeated "nodes" leaves
    // nlohmann the last array, which may have fewer nodes than the first.)
    if (d.node >= 0) {
      const std::string id = d.node < static_cast<int>(g.nodes.size()) ? g.nodes[d.node].id : "";
      if (d.section == "inputs")
        errs.push_back(node_prefix(d.path, id) + "input port " + in_quotes(d.key) +
                       " is connected twice; expected one source per input");
      else
        errs.push_back(node_prefix(d.path, id) + "parameter " + in_quotes(d.key) + " is given twice; expected it once");
      continue;
    }
    errs.push_back(d.path + ": duplicate key; expected each key once");
  }
  return g;
}

Graph load_graph(const std::string& path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) throw ValidationError({path + ": is a folder; expected a graph file (.json)"});
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ValidationError({path + ": cannot open graph file"});
  std::stringstream s;
  s << in.rdbuf();
  return parse_graph(s.str(), path);
}

namespace {

// Parses the VALUE of --set NAME=VALUE: JSON when it reads as JSON (4, true, "x"), else a string.
json parse_set_value(const std::string& text) {
  try {
    return json::parse(text);
  } catch (const json::exception&) {
    return json(text);
  }
}

constexpr std::size_t kMaxStringParam = 4096;

// A parameter value as an error message quotes it: scalars as JSON (a long string cut short),
// arrays and objects by their size.
std::string got_text(const json& v) {
  if (v.is_array()) return "an array of " + std::to_string(v.size()) + " values";
  if (v.is_object()) return "an object of " + std::to_string(v.size()) + " keys";
  if (v.is_string()) return "\"" + shown(v.get_ref<const std::string&>()) + "\"";
  return v.dump();
}

// Whether a graph output's name is a plain file name: it is written as <output folder>/<name>.<ext>,
// so it must not reach out of that folder ("../../x", "/abs/x") nor name it ("", ".", "..").
bool plain_file_name(const std::string& name) {
  if (name.empty() || name == "." || name == "..") return false;
  for (unsigned char c : name)
    if (c == '/' || c == '\\' || c < 0x20 || c == 0x7f) return false;
  return true;
}

bool lies_inside(const fs::path& file, const fs::path& folder) {
  auto [f, _] = std::mismatch(folder.begin(), folder.end(), file.begin(), file.end());
  return f == folder.end() && file != folder;
}

// scallop's own example parts (examples/ of the source tree this was built from, as CMake gives
// it; else found only when the compiler gave this file's absolute path, which ccache with
// CCACHE_BASEDIR does not): the shipped graphs' default part lies there, beside graphs/, so
// defaults inside it are allowed too. Were the shipped graphs' default part beside them, this
// could go.
const fs::path& bundled_examples() {
  static const fs::path dir = [] {
#ifdef SCALLOP_EXAMPLES_DIR
    const fs::path examples(SCALLOP_EXAMPLES_DIR);
#else
    const fs::path examples = fs::path(__FILE__).parent_path().parent_path() / "examples";
#endif
    return examples.is_absolute() && fs::is_directory(examples) ? resolved(examples) : fs::path();
  }();
  return dir;
}

// Whether a graph input's default file lies inside the graph's folder (or scallop's examples).
bool default_inside_graph_folder(const Graph& graph, const std::string& default_path) {
  fs::path p(default_path);
  fs::path file = resolved(p.is_absolute() ? p : graph_folder(graph) / p);
  return lies_inside(file, graph_folder(graph)) ||
         (!bundled_examples().empty() && lies_inside(file, bundled_examples()));
}

// Checks one parameter value against its declaration; returns the canonical value or an error.
std::optional<json> check_param(const ParamDecl& p, const json& v, std::string& error) {
  const std::string got = got_text(v);
  switch (p.kind) {
    case ParamKind::Int:
      if (!v.is_number_integer() && !(v.is_number_float() && v.get<double>() == std::floor(v.get<double>()))) {
        error = "parameter " + in_quotes(p.name) + " must be an integer; got " + got;
        return std::nullopt;
      }
      break;
    case ParamKind::Float:
      if (!v.is_number()) {
        error = "parameter " + in_quotes(p.name) + " must be a number; got " + got;
        return std::nullopt;
      }
      if (!std::isfinite(v.get<double>())) {
        error = "parameter " + in_quotes(p.name) + " must be finite; got " + got;
        return std::nullopt;
      }
      break;
    case ParamKind::Bool:
      if (!v.is_boolean()) {
        error = "parameter " + in_quotes(p.name) + " must be true or false; got " + got;
        return std::nullopt;
      }
      return v;
    case ParamKind::String:
      if (!v.is_string()) {
        error = "parameter " + in_quotes(p.name) + " must be a string; got " + got;
        return std::nullopt;
      }
      // bounded, so that a long graph parameter referred to by many nodes cannot blow up the plan
      if (v.get_ref<const std::string&>().size() > kMaxStringParam) {
        error = "parameter " + in_quotes(p.name) + " is " + std::to_string(v.get_ref<const std::string&>().size()) +
                " bytes long; expected at most " + std::to_string(kMaxStringParam);
        return std::nullopt;
      }
      // a file the node writes: refused before anything runs when it would leave the output folder
      // (an empty one is the node's own error: it says which file it needs)
      if (p.output_path && !v.get_ref<const std::string&>().empty())
        if (auto problem = output_path_problem(v.get<std::string>()); !problem.empty()) {
          error = "parameter " + in_quotes(p.name) + ": " + problem;
          return std::nullopt;
        }
      return v;
    case ParamKind::Choice:
      if (!v.is_string() || std::find(p.choices.begin(), p.choices.end(), v.get<std::string>()) == p.choices.end()) {
        error = "parameter " + in_quotes(p.name) + " must be one of " + join_names(p.choices) + "; got " + got;
        return std::nullopt;
      }
      return v;
  }
  double x = v.get<double>();
  if ((p.min && x < *p.min) || (p.max && x > *p.max)) {
    std::ostringstream s;
    s << "parameter " << in_quotes(p.name) << " = " << got << " is out of range; expected ";
    if (p.min && p.max) s << *p.min << " .. " << *p.max;
    else if (p.min) s << "at least " << *p.min;
    else s << "at most " << *p.max;
    if (!p.unit.empty()) s << " " << p.unit;
    error = s.str();
    return std::nullopt;
  }
  if (p.kind == ParamKind::Int) return json(static_cast<long long>(x));
  return json(x);
}

}  // namespace

Plan compile(const Graph& graph, const Registry& registry, const CompileOptions& options) {
  std::vector<std::string> errs = graph.errors;
  Plan plan;
  plan.graph_name = graph.name;
  plan.graph_path = graph.path;
  plan.inputs = graph.inputs;

  // Graph parameters, then --set overrides (graph-level and node-level).
  std::map<std::string, json> gparams;
  for (const auto& [k, p] : graph.params) gparams[k] = p.value;
  std::map<std::string, std::map<std::string, json>> node_sets;
  // "--set NAME=VALUE" as given, by graph parameter and by node id and parameter: a value it set
  // that is refused (or a node it makes fail) is named by the --set, not only by the node.
  std::map<std::string, std::string> gparam_set_text;
  std::map<std::string, std::map<std::string, std::string>> node_set_text;
  std::map<std::string, int> index_of;
  for (std::size_t i = 0; i < graph.nodes.size(); ++i) {
    const auto& n = graph.nodes[i];
    if (n.id.empty()) continue;
    if (index_of.count(n.id))
      errs.push_back(node_prefix("nodes[" + std::to_string(i) + "].id", n.id) + "duplicate node id; expected ids to be unique");
    else
      index_of[n.id] = static_cast<int>(i);
  }
  for (const auto& item : options.sets) {
    auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      errs.push_back("--set " + item + ": expected NAME=VALUE");
      continue;
    }
    std::string name = item.substr(0, eq);
    if (!too_deep_at(item.substr(eq + 1), kMaxGraphNesting).empty()) {
      errs.push_back("--set " + shown(name) + ": value nested more than " + std::to_string(kMaxGraphNesting) +
                     " levels deep; expected a number, a string, true or false");
      continue;
    }
    json value = parse_set_value(item.substr(eq + 1));
    const std::string set_text = "--set " + shown(name) + "=" + shown(item.substr(eq + 1));
    auto dot = name.find('.');
    if (dot == std::string::npos) {
      if (!gparams.count(name))
        errs.push_back("--set " + name + ": unknown graph parameter " + in_quotes(name) + "; expected one of: " +
                       join_keys(gparams));
      else {
        gparams[name] = value;
        gparam_set_text[name] = set_text;
      }
    } else {
      std::string id = name.substr(0, dot), key = name.substr(dot + 1);
      if (!index_of.count(id))
        errs.push_back("--set " + name + ": unknown node " + in_quotes(id) + "; expected one of: " + join_keys(index_of));
      else {
        node_sets[id][key] = value;
        node_set_text[id][key] = set_text;
      }
    }
  }
  plan.graph_params = json(gparams);

  // Nodes: type, parameters, input ports.
  plan.nodes.resize(graph.nodes.size());
  for (std::size_t i = 0; i < graph.nodes.size(); ++i) {
    const auto& n = graph.nodes[i];
    auto& pn = plan.nodes[i];
    pn.id = n.id;
    std::string at = "nodes[" + std::to_string(i) + "]";
    if (n.type.empty()) continue;  // reported while parsing
    pn.decl = registry.find(n.type);
    if (!pn.decl) {
      std::string best;
      std::size_t best_d = 4;
      for (const auto& [t, d] : registry.nodes()) {
        const std::size_t longer = std::max(t.size(), n.type.size()), shorter = std::min(t.size(), n.type.size());
        if (longer - shorter >= best_d) continue;  // the distance is at least the difference in length
        if (auto e = edit_distance(t, n.type); e < best_d) best_d = e, best = t;
      }
      errs.push_back(node_prefix(at + ".type", n.id) + "unknown node type " + in_quotes(n.type) + "; expected " +
                     (best.empty() ? std::string("a registered type") : "a registered type such as " + in_quotes(best)) +
                     " (see 'scallop nodes')");
      continue;
    }
    const NodeDecl& decl = *pn.decl;
    json given = n.params;
    std::map<std::string, std::string> origin;  // where each value came from, for messages
    for (const auto& [k, v] : given.items()) origin[k] = at + ".params." + shown(k);
    for (const auto& [k, v] : node_sets[n.id]) {
      given[k] = v;
      origin[k] = node_set_text[n.id][k];
      pn.set_by[k] = origin[k];
    }
    json resolved = json::object();
    for (const auto& [k, v] : given.items()) {
      const ParamDecl* p = decl.find_param(k);
      if (!p) {
        std::vector<std::string> names;
        for (const auto& pd : decl.params) names.push_back(pd.name);
        errs.push_back(node_prefix(origin[k], n.id) + "unknown parameter " + in_quotes(k) + "; expected one of: " +
                       join_names(names));
        continue;
      }
      const json* value = &v;  // not copied: a large graph parameter may be referred to by many nodes
      if (v.is_string() && !v.get<std::string>().empty() && v.get<std::string>()[0] == '$') {
        std::string ref = v.get<std::string>().substr(1);
        if (!gparams.count(ref)) {
          errs.push_back(node_prefix(origin[k], n.id) + "unknown graph parameter " + in_quotes("$" + ref) +
                         "; expected one of: " + join_keys(gparams));
          continue;
        }
        value = &gparams[ref];
        if (auto set = gparam_set_text.find(ref); set != gparam_set_text.end()) {
          origin[k] = set->second + " (" + origin[k] + ")";  // the --set gave the value, the node refuses it
          pn.set_by[k] = set->second;
        }
      }
      std::string error;
      if (auto ok = check_param(*p, *value, error)) resolved[k] = *ok;
      else errs.push_back(node_prefix(origin[k], n.id) + error);
    }
    for (const auto& p : decl.params) {
      if (resolved.contains(p.name) || given.contains(p.name)) continue;
      if (p.default_value.is_null())
        errs.push_back(node_prefix(at + ".params", n.id) + "missing required parameter " + in_quotes(p.name) + " (" +
                       to_string(p.kind) + (p.unit.empty() ? "" : ", " + p.unit) + ")");
      else
        resolved[p.name] = p.default_value;
    }
    pn.params = resolved;

    std::set<std::string> connected;
    for (const auto& [port, src] : n.inputs) {
      std::string pat = at + ".inputs." + shown(port);
      const PortDecl* pd = decl.find_input(port);
      if (!pd) {
        std::vector<std::string> names;
        for (const auto& q : decl.inputs) names.push_back(q.name);
        errs.push_back(node_prefix(pat, n.id) + "unknown input port " + in_quotes(port) + "; expected one of: " +
                       join_names(names));
        continue;
      }
      connected.insert(port);
      Source s;
      std::string src_type;
      if (!src.empty() && src[0] == '@') {
        s.port = src.substr(1);
        auto gi = graph.inputs.find(s.port);
        if (gi == graph.inputs.end()) {
          errs.push_back(node_prefix(pat, n.id) + "unknown graph input " + in_quotes(src) + "; expected one of: " +
                         join_keys(graph.inputs));
          continue;
        }
        src_type = gi->second.type;
      } else {
        auto dot = src.find('.');
        std::string sid = dot == std::string::npos ? src : src.substr(0, dot);
        if (dot == std::string::npos || !index_of.count(sid)) {
          errs.push_back(node_prefix(pat, n.id) + "unknown source " + in_quotes(src) +
                         "; expected '<node id>.<output port>' or '@<graph input>'");
          continue;
        }
        s.node = index_of[sid];
        s.port = src.substr(dot + 1);
        const NodeDecl* sd = registry.find(graph.nodes[s.node].type);
        if (!sd) continue;  // its unknown type is reported already
        const PortDecl* op = sd->find_output(s.port);
        if (!op) {
          std::vector<std::string> names;
          for (const auto& q : sd->outputs) names.push_back(q.name);
          errs.push_back(node_prefix(pat, n.id) + "node " + in_quotes(sid) + " has no output " + in_quotes(s.port) +
                         "; expected one of: " + join_names(names));
          continue;
        }
        src_type = op->type;
      }
      if (src_type != pd->type) {
        errs.push_back(node_prefix(pat, n.id) + "type mismatch: " + in_quotes(src) + " is " + src_type + "; expected " +
                       pd->type);
        continue;
      }
      pn.inputs.emplace_back(port, s);
    }
    for (const auto& pd : decl.inputs)
      if (pd.required && !connected.count(pd.name))
        errs.push_back(node_prefix(at + ".inputs", n.id) + "missing required input " + in_quotes(pd.name) + " (" +
                       pd.type + ")");
    // Keep inputs in declaration order so cache keys do not depend on JSON key order.
    std::sort(pn.inputs.begin(), pn.inputs.end(), [&](const auto& a, const auto& b) {
      auto pos = [&](const std::string& name) {
        for (std::size_t q = 0; q < decl.inputs.size(); ++q)
          if (decl.inputs[q].name == name) return q;
        return decl.inputs.size();
      };
      return pos(a.first) < pos(b.first);
    });
  }

  // Graph outputs.
  for (const auto& [name, src] : graph.outputs) {
    if (!plain_file_name(name)) {
      errs.push_back("outputs." + shown(name) + ": output name " + in_quotes(name) +
                     " is not a plain file name; expected one without '/', '\\' or control characters, not '.' or '..'");
      continue;
    }
    auto dot = src.find('.');
    std::string sid = dot == std::string::npos ? src : src.substr(0, dot);
    if (dot == std::string::npos || !index_of.count(sid)) {
      errs.push_back("outputs." + shown(name) + ": unknown source " + in_quotes(src) + "; expected '<node id>.<output port>'");
      continue;
    }
    Source s{index_of[sid], src.substr(dot + 1)};
    const NodeDecl* sd = plan.nodes[s.node].decl;
    if (sd && !sd->find_output(s.port)) {
      std::vector<std::string> names;
      for (const auto& q : sd->outputs) names.push_back(q.name);
      errs.push_back("outputs." + shown(name) + ": node " + in_quotes(sid) + " has no output " + in_quotes(s.port) +
                     "; expected one of: " + join_names(names));
      continue;
    }
    plan.outputs.emplace_back(name, s);
  }

  // Graph inputs the caller must give, and the default files of those it does not: they must lie in
  // the graph's folder (a graph handed over must not read files from elsewhere on the disk;
  // --input reads any file, that is the user's choice).
  for (const auto& [name, in] : graph.inputs) {
    if (options.provided_inputs.count(name)) continue;
    if (in.default_path.empty()) {
      if (options.require_inputs)
        errs.push_back("inputs." + shown(name) + ": graph input " + in_quotes(name) + " is not given; expected --input " +
                       name + "=PATH");
    } else if (!default_inside_graph_folder(graph, in.default_path)) {
      errs.push_back("inputs." + shown(name) + ".default: default file '" + shown(in.default_path, 1024) +
                     "' lies outside the graph's folder '" + graph_folder(graph).string() + "'" +
                     "; expected a file inside it, or one given with --input " + name + "=PATH");
    }
  }

  // Dependencies and a topological order (Kahn); what is left over lies on a cycle.
  const int n = static_cast<int>(plan.nodes.size());
  for (int i = 0; i < n; ++i) {
    std::set<int> deps;
    for (const auto& [port, s] : plan.nodes[i].inputs)
      if (s.node >= 0) deps.insert(s.node);
    plan.nodes[i].deps.assign(deps.begin(), deps.end());
    for (int d : deps) plan.nodes[d].dependents.push_back(i);
  }
  std::vector<int> indeg(n);
  for (int i = 0; i < n; ++i) indeg[i] = static_cast<int>(plan.nodes[i].deps.size());
  std::vector<int> ready;
  for (int i = n - 1; i >= 0; --i)
    if (indeg[i] == 0) ready.push_back(i);
  while (!ready.empty()) {
    int i = ready.back();
    ready.pop_back();
    plan.order.push_back(i);
    for (int d : plan.nodes[i].dependents)
      if (--indeg[d] == 0) ready.push_back(d);
  }
  if (static_cast<int>(plan.order.size()) < n) {
    // Walk back along unfinished dependencies from a node on the cycle until a node repeats.
    int start = -1;
    for (int i = 0; i < n && start < 0; ++i)
      if (indeg[i] > 0) start = i;
    std::vector<int> walk;
    std::vector<int> seen_at(n, -1);
    int cur = start;
    while (seen_at[cur] < 0) {
      seen_at[cur] = static_cast<int>(walk.size());
      walk.push_back(cur);
      for (int d : plan.nodes[cur].deps)
        if (indeg[d] > 0) {
          cur = d;
          break;
        }
    }
    std::vector<int> cycle(walk.begin() + seen_at[cur], walk.end());
    std::reverse(cycle.begin(), cycle.end());  // producer -> consumer order
    std::rotate(cycle.begin(), std::min_element(cycle.begin(), cycle.end()), cycle.end());  // stable text
    std::string text;
    for (int c : cycle) text += plan.nodes[c].id + " -> ";
    text += plan.nodes[cycle.front()].id;
    errs.push_back("nodes: cycle " + text + "; expected an acyclic graph");
  }
  if (!errs.empty()) throw ValidationError(errs);
  return plan;
}

std::string to_dot(const Plan& plan) {
  std::ostringstream s;
  s << "digraph \"" << (plan.graph_name.empty() ? "scallop" : plan.graph_name) << "\" {\n  rankdir=LR;\n"
    << "  node [shape=box, fontname=\"Helvetica\"];\n";
  for (const auto& [name, in] : plan.inputs) s << "  \"@" << name << "\" [shape=ellipse];\n";
  for (const auto& n : plan.nodes)
    s << "  \"" << n.id << "\" [label=\"" << n.id << "\\n" << (n.decl ? n.decl->type : "?") << "\"];\n";
  for (const auto& n : plan.nodes)
    for (const auto& [port, src] : n.inputs) {
      std::string from = src.node < 0 ? "@" + src.port : plan.nodes[src.node].id;
      s << "  \"" << from << "\" -> \"" << n.id << "\" [label=\"" << (src.node < 0 ? "" : src.port + " → ") << port
        << "\"];\n";
    }
  for (const auto& [name, src] : plan.outputs) {
    s << "  \"out:" << name << "\" [shape=note, label=\"" << name << "\"];\n";
    s << "  \"" << plan.nodes[src.node].id << "\" -> \"out:" << name << "\" [label=\"" << src.port << "\"];\n";
  }
  s << "}\n";
  return s.str();
}

}  // namespace scallop
