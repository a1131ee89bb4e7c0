// The `scallop` command: run, batch, validate, nodes, dot.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "engine/runner.h"
#include "nodes/all_nodes.h"
#include "nodes/types/document.h"

namespace fs = std::filesystem;
using namespace scallop;

namespace {

struct CommonOptions {
  std::vector<std::string> sets;
  std::string cache_dir;
  bool no_cache = false;
  bool explain = false;
  bool quiet = false;
  std::string events_path;
  int threads = 0;
};

void add_common(CLI::App* cmd, CommonOptions& o) {
  cmd->add_option("--set", o.sets, "NAME=VALUE: a graph parameter (tool_radius=4) or node parameter (knn.k=16)")
      ->take_all();
  cmd->add_option("--cache", o.cache_dir, "disk cache folder (default: $XDG_CACHE_HOME/scallop)");
  cmd->add_flag("--no-cache", o.no_cache, "do not read or write the disk cache");
  cmd->add_flag("--explain", o.explain, "say for each node why the cache hit or missed");
  cmd->add_option("--events", o.events_path, "write progress events as JSON lines to FILE");
  cmd->add_flag("-q,--quiet", o.quiet, "no per-node progress on stderr");
  cmd->add_option("--threads", o.threads,
                  "at most N threads (default: every core); 1 runs one node at a time, so the events' "
                  "peak_mib is each node's own")
      ->check(CLI::Range(1, 1024));
}

// Loads a graph or prints its errors; returns false on failure.
bool load(const std::string& path, Graph& graph) {
  try {
    graph = load_graph(path);
    return true;
  } catch (const ValidationError& e) {
    for (const auto& m : e.errors) std::cerr << "error: " << m << "\n";
    return false;
  }
}

// Exit statuses of run and batch (README, "The scallop command").
constexpr int kExitDone = 0;             // done; every certificate passed (or there was none)
constexpr int kExitNodeFailed = 1;       // a node (or writing an output) failed
constexpr int kExitInvalid = 2;          // invalid graph, input file or arguments (also an input file
                                         // the reader finds malformed: PartResult::bad_input)
constexpr int kExitCertificateFailed = 3;  // ran to the end, but a certificate failed: do not cut

// A certificate is a graph output of type Report whose JSON has a boolean "pass" (post.simulate's
// report): found by what it says, not by which node made it.
struct Certificate {
  std::string output;  // graph output name
  bool pass = false;
  std::vector<std::string> reasons;
  std::string figures;  // "scallop_max 0.05, ..." : the headline numbers it has
};

std::vector<Certificate> certificates(const PartResult& r) {
  std::vector<Certificate> out;
  for (const auto& [name, value] : r.run.outputs) {
    auto report = std::dynamic_pointer_cast<const Report>(value);
    if (!report || !report->data.is_object() || !report->data.contains("pass") || !report->data["pass"].is_boolean())
      continue;
    const auto& d = report->data;
    Certificate c;
    c.output = name;
    c.pass = d["pass"].get<bool>();
    if (d.contains("fail_reasons") && d["fail_reasons"].is_array())
      for (const auto& m : d["fail_reasons"]) c.reasons.push_back(m.is_string() ? m.get<std::string>() : m.dump());
    for (const char* key : {"scallop_max", "scallop_max_interior", "gouge_max", "uncut_fraction"})
      if (d.contains(key) && d[key].is_number()) {
        char buf[64];
        std::snprintf(buf, sizeof buf, "%s %.4g", key, d[key].get<double>());
        c.figures += (c.figures.empty() ? "" : ", ") + std::string(buf);
      }
    if (!c.pass && c.reasons.empty()) c.reasons.push_back("no reason given");
    out.push_back(std::move(c));
  }
  return out;
}

// "certificate 'report': pass (scallop_max 0.048, ...)" or
// "certificate 'report': FAIL, do not cut: reason; reason (scallop_max ...)".
std::string verdict_line(const Certificate& c) {
  std::string line = "certificate '" + c.output + "': ";
  if (c.pass) return line + "pass" + (c.figures.empty() ? "" : " (" + c.figures + ")");
  line += "FAIL, do not cut: ";
  for (std::size_t i = 0; i < c.reasons.size(); ++i) line += (i ? "; " : "") + c.reasons[i];
  return line + (c.figures.empty() ? "" : " (" + c.figures + ")");
}

// "pass", "FAIL" or "none" for a part's certificates together.
std::string certificate_status(const std::vector<Certificate>& cs) {
  if (cs.empty()) return "none";
  for (const auto& c : cs)
    if (!c.pass) return "FAIL";
  return "pass";
}

struct Sinks {
  std::unique_ptr<DiskCache> cache;
  std::unique_ptr<JsonLinesSink> json;
  std::unique_ptr<TerminalReporter> terminal;
  EventFanout fanout;
};

void open_sinks(const CommonOptions& o, Sinks& s, int total_nodes) {
  if (!o.no_cache) s.cache = std::make_unique<DiskCache>(o.cache_dir.empty() ? DiskCache::default_dir() : o.cache_dir);
  if (!o.events_path.empty()) s.json = std::make_unique<JsonLinesSink>(o.events_path);
  s.terminal = std::make_unique<TerminalReporter>(stderr, o.explain, o.quiet);
  s.terminal->set_total(total_nodes);
  s.fanout.add(s.json.get());
  s.fanout.add(s.terminal.get());
}

int cmd_run(const std::string& graph_path, const std::vector<std::string>& input_args, const std::string& out_dir,
            const CommonOptions& o) {
  Graph graph;
  if (!load(graph_path, graph)) return kExitInvalid;
  PartRequest req;
  for (const auto& a : input_args) {
    auto eq = a.find('=');
    if (eq == std::string::npos) {
      std::cerr << "error: --input " << a << ": expected NAME=PATH\n";
      return kExitInvalid;
    }
    req.inputs[a.substr(0, eq)] = a.substr(eq + 1);
  }
  req.sets = o.sets;
  req.out_dir = out_dir;
  Sinks sinks;
  open_sinks(o, sinks, static_cast<int>(graph.nodes.size()));
  req.cache = sinks.cache.get();
  req.events = &sinks.fanout;
  PartResult r = run_part(graph, builtin_registry(), req);
  if (r.run.nodes.empty() && !r.ok) {  // never started: validation or input errors
    for (const auto& m : r.errors) std::cerr << "error: " << m << "\n";
    return kExitInvalid;
  }
  int warnings = 0;
  for (const auto& n : r.run.nodes) warnings += static_cast<int>(n.warnings.size());
  std::fprintf(stderr, "%s in %.3f s (%d nodes ran, %d from cache%s)\n", r.ok ? "done" : "FAILED", r.seconds,
               r.run.executed(),
               static_cast<int>(std::count_if(r.run.nodes.begin(), r.run.nodes.end(),
                                              [](const NodeRun& n) { return n.status == "cached"; })),
               warnings ? (", " + std::to_string(warnings) + " warning" + (warnings > 1 ? "s" : "")).c_str() : "");
  for (const auto& w : r.written) std::cout << "wrote " << w << "\n";
  std::cout.flush();
  for (const auto& m : r.errors) std::cerr << "error: " << m << "\n";
  bool certified = true;
  for (const auto& c : certificates(r)) {
    certified &= c.pass;
    if (!c.pass || !o.quiet) std::cerr << verdict_line(c) << "\n";
  }
  if (!r.ok) return r.bad_input ? kExitInvalid : kExitNodeFailed;
  return certified ? kExitDone : kExitCertificateFailed;
}

// Says on stderr where parts whose file names share a stem write (batch_part_names).
void say_shared_names(const std::vector<std::string>& parts, const std::vector<std::string>& names,
                      const std::string& out_dir) {
  std::map<std::string, std::vector<std::size_t>> by_stem;
  for (std::size_t i = 0; i < parts.size(); ++i) by_stem[fs::path(parts[i]).stem().string()].push_back(i);
  for (const auto& [stem, group] : by_stem) {
    if (group.size() == 1) continue;
    std::string files, folders;
    for (std::size_t k = 0; k < group.size(); ++k) {
      const char* sep = k == 0 ? "" : k + 1 == group.size() ? " and " : ", ";
      files += sep + parts[group[k]];
      folders += sep + (fs::path(out_dir) / names[group[k]]).string() + "/";
    }
    std::cerr << "note: parts " << files << " share the name '" << stem << "'; their outputs go to " << folders
              << " and they are named so in messages\n";
  }
}

int cmd_batch(const std::string& graph_path, const std::vector<std::string>& parts, int jobs,
              const std::string& input_name_arg, const std::string& out_dir, const CommonOptions& o) {
  Graph graph;
  if (!load(graph_path, graph)) return kExitInvalid;
  std::string input_name = input_name_arg;
  if (input_name.empty()) {
    if (graph.inputs.size() != 1) {
      std::cerr << "error: the graph has " << graph.inputs.size()
                << " inputs; say which one the parts bind to with --part-input NAME\n";
      return kExitInvalid;
    }
    input_name = graph.inputs.begin()->first;
  }
  PartRequest common;
  common.sets = o.sets;
  common.out_dir = out_dir;
  Sinks sinks;
  open_sinks(o, sinks, static_cast<int>(graph.nodes.size() * parts.size()));
  common.cache = sinks.cache.get();
  common.events = &sinks.fanout;
  say_shared_names(parts, batch_part_names(parts), out_dir);
  auto results = run_batch(graph, builtin_registry(), input_name, parts, jobs, common);

  nlohmann::json summary = nlohmann::json::array();
  std::vector<std::string> failed, uncertified;
  bool node_failed = false;  // a part failed for another reason than bad input: exit 1, not 2
  std::vector<std::string> verdicts;  // printed after the table
  std::printf("\n%-32s %-6s %-11s %10s  %s\n", "part", "status", "certificate", "seconds", "outputs / first error");
  for (std::size_t i = 0; i < results.size(); ++i) {
    const auto& r = results[i];
    const auto certs = certificates(r);
    const std::string cert = certificate_status(certs);
    std::printf("%-32s %-6s %-11s %10.3f  %s\n", r.part.c_str(), r.ok ? "ok" : "FAILED", cert.c_str(), r.seconds,
                r.ok ? std::to_string(r.written.size()).c_str() : r.errors.front().c_str());
    if (!r.ok) failed.push_back(r.part);
    node_failed |= !r.ok && !r.bad_input;
    if (cert == "FAIL") uncertified.push_back(r.part);
    nlohmann::json reasons = nlohmann::json::array(), warnings = nlohmann::json::array();
    for (const auto& c : certs) {
      if (!c.pass || !o.quiet) verdicts.push_back("part '" + r.part + "': " + verdict_line(c));
      for (const auto& m : c.reasons) reasons.push_back(m);
    }
    for (const auto& n : r.run.nodes)
      for (const auto& w : n.warnings) warnings.push_back("node '" + n.id + "' (" + n.type + "): " + w);
    summary.push_back({{"part", r.part}, {"input", parts[i]}, {"ok", r.ok}, {"certificate", cert},
                       {"certificate_reasons", reasons}, {"seconds", r.seconds}, {"errors", r.errors},
                       {"warnings", warnings}, {"outputs", r.written}});
  }
  fs::create_directories(out_dir);
  std::ofstream(fs::path(out_dir) / "summary.json")
      << nlohmann::json{{"graph", graph_path},
                        {"parts_failed", failed.size()},
                        {"certificates_failed", uncertified.size()},
                        {"parts", summary}}
             .dump(2)
      << "\n";
  std::printf("%zu of %zu parts ok, %zu certificate(s) failed; summary in %s\n", results.size() - failed.size(),
              results.size(), uncertified.size(), (fs::path(out_dir) / "summary.json").string().c_str());
  std::fflush(stdout);
  for (const auto& v : verdicts) std::fprintf(stderr, "%s\n", v.c_str());
  auto names = [](const std::vector<std::string>& v) {
    std::string s;
    for (const auto& f : v) s += (s.empty() ? "" : ", ") + f;
    return s;
  };
  if (!uncertified.empty())
    std::fprintf(stderr, "error: %zu certificate(s) failed, do not cut: %s\n", uncertified.size(),
                 names(uncertified).c_str());
  if (!failed.empty()) {
    std::fprintf(stderr, "error: %zu part(s) failed: %s\n", failed.size(), names(failed).c_str());
    return node_failed ? kExitNodeFailed : kExitInvalid;
  }
  return uncertified.empty() ? kExitDone : kExitCertificateFailed;
}

int cmd_validate(const std::string& graph_path, const std::vector<std::string>& sets) {
  Graph graph;
  if (!load(graph_path, graph)) return 2;
  try {
    CompileOptions opt;
    opt.sets = sets;
    opt.require_inputs = false;
    compile(graph, builtin_registry(), opt);
  } catch (const ValidationError& e) {
    for (const auto& m : e.errors) std::cerr << "error: " << m << "\n";
    std::cerr << e.errors.size() << " error(s) in " << graph_path << "\n";
    return 2;
  }
  std::cout << graph_path << ": ok (" << graph.nodes.size() << " nodes)\n";
  return 0;
}

int cmd_nodes(const std::string& type, bool as_json, bool markdown) {
  const auto& reg = builtin_registry();
  if (!type.empty() && !reg.find(type)) {
    std::cerr << "error: unknown node type '" << type << "'\n";
    return 2;
  }
  if (as_json) {
    nlohmann::json j = nlohmann::json::array();
    for (const auto& [t, d] : reg.nodes())
      if (type.empty() || t == type) j.push_back(to_json(d));
    std::cout << (type.empty() ? j : j[0]).dump(2) << "\n";
    return 0;
  }
  if (type.empty() && !markdown) {
    for (const auto& [t, d] : reg.nodes()) std::printf("%-24s v%-3d %s\n", t.c_str(), d.version, d.description.c_str());
    return 0;
  }
  for (const auto& [t, d] : reg.nodes())
    if (type.empty() || t == type) std::cout << to_markdown(d);
  return 0;
}

int cmd_dot(const std::string& graph_path) {
  Graph graph;
  if (!load(graph_path, graph)) return 2;
  try {
    CompileOptions opt;
    opt.require_inputs = false;
    std::cout << to_dot(compile(graph, builtin_registry(), opt));
  } catch (const ValidationError& e) {
    for (const auto& m : e.errors) std::cerr << "error: " << m << "\n";
    return 2;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"scallop: certified ball-end finishing tool paths straight from point clouds"};
  app.require_subcommand(1);

  CommonOptions run_opts;
  std::string run_graph, run_out = "scallop-out";
  std::vector<std::string> run_inputs;
  auto* run = app.add_subcommand("run", "run a graph on one part");
  run->add_option("graph", run_graph, "graph JSON file")->required();
  run->add_option("--input", run_inputs, "NAME=PATH: a graph input file")->take_all();
  run->add_option("-o,--out", run_out, "output folder (default scallop-out)");
  add_common(run, run_opts);

  CommonOptions batch_opts;
  std::string batch_graph, batch_out, batch_input;
  std::vector<std::string> batch_parts;
  int batch_jobs = 2;
  auto* batch = app.add_subcommand("batch", "run a graph on many parts, outputs in DIR/<part stem>/ (DIR/<stem>_<extension>/ where stems clash)");
  batch->add_option("graph", batch_graph, "graph JSON file")->required();
  batch->add_option("parts", batch_parts, "part files")->required();
  batch->add_option("-j,--jobs", batch_jobs, "parts in flight at once")->check(CLI::Range(1, 256));
  batch->add_option("--part-input", batch_input, "graph input the parts bind to (default: the only one)");
  batch->add_option("-o,--out", batch_out, "output folder")->required();
  add_common(batch, batch_opts);

  std::string val_graph;
  std::vector<std::string> val_sets;
  auto* validate = app.add_subcommand("validate", "check a graph; print every error (exit 2) or ok");
  validate->add_option("graph", val_graph, "graph JSON file")->required();
  validate->add_option("--set", val_sets, "NAME=VALUE overrides to check too")->take_all();

  std::string nodes_type;
  bool nodes_json = false, nodes_md = false;
  auto* nodes = app.add_subcommand("nodes", "node reference, generated from the declarations");
  nodes->add_option("type", nodes_type, "one node type");
  nodes->add_flag("--json", nodes_json, "as JSON");
  nodes->add_flag("--markdown", nodes_md, "as Markdown (the README reference)");

  std::string dot_graph;
  auto* dot = app.add_subcommand("dot", "the graph in Graphviz dot");
  dot->add_option("graph", dot_graph, "graph JSON file")->required();

  CLI11_PARSE(app, argc, argv);
  const int threads = *run ? run_opts.threads : *batch ? batch_opts.threads : 0;
  std::unique_ptr<tbb::global_control> thread_limit;
  if (threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                         static_cast<std::size_t>(threads));
  try {
    if (*run) return cmd_run(run_graph, run_inputs, run_out, run_opts);
    if (*batch) return cmd_batch(batch_graph, batch_parts, batch_jobs, batch_input, batch_out, batch_opts);
    if (*validate) return cmd_validate(val_graph, val_sets);
    if (*nodes) return cmd_nodes(nodes_type, nodes_json, nodes_md);
    if (*dot) return cmd_dot(dot_graph);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
