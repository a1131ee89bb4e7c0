// The `scallop` command: run, batch, validate, nodes, dot.
#include <CLI/CLI.hpp>
#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <sstream>

#include "cli/slurm_batch.h"
#include "engine/memory.h"
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

// One part's record: its entry in summary.json, and what `run --result` writes for a batch task
// that ran elsewhere (a Slurm task) to hand back. "bad_input" (for the exit status) and
// "verdicts" (the certificate lines for stderr) are for the batch itself, not summary.json.
nlohmann::json part_record(const PartResult& r, const std::string& input, bool quiet) {
  nlohmann::json reasons = nlohmann::json::array(), warnings = nlohmann::json::array(),
                 verdicts = nlohmann::json::array();
  const auto certs = certificates(r);
  for (const auto& c : certs) {
    if (!c.pass || !quiet) verdicts.push_back(verdict_line(c));
    for (const auto& m : c.reasons) reasons.push_back(m);
  }
  for (const auto& n : r.run.nodes)
    for (const auto& w : n.warnings) warnings.push_back("node '" + n.id + "' (" + n.type + "): " + w);
  // disk-cached nodes taken from the cache, and run (missed); nodes not cached on disk count in neither
  int hits = 0, misses = 0;
  for (const auto& n : r.run.nodes) {
    hits += n.cache == "hit";
    misses += n.cache == "miss" && (n.status == "ok" || n.status == "failed");
  }
  return {{"part", r.part}, {"input", input}, {"ok", r.ok}, {"certificate", certificate_status(certs)},
          {"certificate_reasons", reasons}, {"seconds", r.seconds}, {"errors", r.errors},
          {"warnings", warnings}, {"outputs", r.written}, {"nodes_run", r.run.executed()},
          {"cache_hits", hits}, {"cache_misses", misses}, {"bad_input", r.bad_input}, {"verdicts", verdicts}};
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

// Writes a part's record for `run --result` whole or not at all (temp file + rename), so that a
// batch waiting for it on another host never reads half of one.
void write_record(const std::string& path, const nlohmann::json& record) {
  if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path());
  const std::string tmp = temp_path_beside(path);
  std::ofstream out(tmp);
  out << record.dump(2) << "\n";
  out.close();
  if (!out) throw std::runtime_error("cannot write '" + tmp + "'");
  fs::rename(tmp, path);
}

int cmd_run(const std::string& graph_path, const std::vector<std::string>& input_args, const std::string& out_dir,
            const std::string& part, const std::string& result_path, const CommonOptions& o) {
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
  req.part = part;
  Sinks sinks;
  open_sinks(o, sinks, static_cast<int>(graph.nodes.size()));
  req.cache = sinks.cache.get();
  req.events = &sinks.fanout;
  PartResult r = run_part(graph, builtin_registry(), req);
  if (!result_path.empty())
    write_record(result_path, part_record(r, req.inputs.empty() ? "" : req.inputs.begin()->second, o.quiet));
  if (r.run.nodes.empty() && !r.ok) {  // never started: validation or input errors
    for (const auto& m : r.errors) std::cerr << "error: " << m << "\n";
    return kExitInvalid;
  }
  int warnings = 0;
  for (const auto& n : r.run.nodes) warnings += static_cast<int>(n.warnings.size());
  // The run's memory peak is the largest of the nodes' own: the executor restarts the kernel's
  // high-water mark when a node starts with none running, which also restarts the ru_maxrss that
  // /usr/bin/time reports (so that reports only the peak since the last such start).
  double peak_mib = static_cast<double>(peak_resident_bytes()) / (1024.0 * 1024.0);
  for (const auto& n : r.run.nodes) peak_mib = std::max(peak_mib, n.peak_mib);
  std::fprintf(stderr, "%s in %.3f s (%d nodes ran, %d from cache%s), peak %.0f MiB\n", r.ok ? "done" : "FAILED",
               r.seconds, r.run.executed(),
               static_cast<int>(std::count_if(r.run.nodes.begin(), r.run.nodes.end(),
                                              [](const NodeRun& n) { return n.status == "cached"; })),
               warnings ? (", " + std::to_string(warnings) + " warning" + (warnings > 1 ? "s" : "")).c_str() : "",
               peak_mib);
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

// The graph input the parts of a batch bind to: --part-input, else the graph's only input; ""
// after saying why not.
std::string part_input_name(const Graph& graph, const std::string& input_name_arg) {
  if (!input_name_arg.empty()) return input_name_arg;
  if (graph.inputs.size() != 1) {
    std::cerr << "error: the graph has " << graph.inputs.size()
              << " inputs; say which one the parts bind to with --part-input NAME\n";
    return "";
  }
  return graph.inputs.begin()->first;
}

// The table, DIR/summary.json and the exit status of a batch, from each part's record
// (part_record), whichever executor ran the parts; `extra` joins summary.json's top level.
int report_batch(const std::string& graph_path, const std::vector<nlohmann::json>& records,
                 const std::string& out_dir, const nlohmann::json& extra = nlohmann::json::object()) {
  nlohmann::json summary = nlohmann::json::array();
  std::vector<std::string> failed, uncertified;
  bool node_failed = false;  // a part failed for another reason than bad input: exit 1, not 2
  std::vector<std::string> verdicts;  // printed after the table
  std::printf("\n%-32s %-6s %-11s %10s  %s\n", "part", "status", "certificate", "seconds", "outputs / first error");
  for (const auto& record : records) {
    const std::string part = record["part"], cert = record["certificate"];
    const bool ok = record["ok"];
    const std::string first_error = record["errors"].empty() ? "" : record["errors"][0].get<std::string>();
    std::printf("%-32s %-6s %-11s %10.3f  %s\n", part.c_str(), ok ? "ok" : "FAILED", cert.c_str(),
                record["seconds"].get<double>(), ok ? std::to_string(record["outputs"].size()).c_str() : first_error.c_str());
    if (!ok) failed.push_back(part);
    node_failed |= !ok && !record["bad_input"].get<bool>();
    if (cert == "FAIL") uncertified.push_back(part);
    for (const auto& v : record["verdicts"]) verdicts.push_back("part '" + part + "': " + v.get<std::string>());
    nlohmann::json entry = record;
    entry.erase("bad_input");
    entry.erase("verdicts");
    summary.push_back(entry);
  }
  fs::create_directories(out_dir);
  nlohmann::json top = {{"graph", graph_path},
                        {"parts_failed", failed.size()},
                        {"certificates_failed", uncertified.size()},
                        {"parts", summary}};
  top.update(extra);
  std::ofstream(fs::path(out_dir) / "summary.json") << top.dump(2) << "\n";
  std::printf("%zu of %zu parts ok, %zu certificate(s) failed; summary in %s\n", records.size() - failed.size(),
              records.size(), uncertified.size(), (fs::path(out_dir) / "summary.json").string().c_str());
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

int cmd_batch(const std::string& graph_path, const std::vector<std::string>& parts, int jobs,
              const std::string& input_name_arg, const std::string& out_dir, const CommonOptions& o) {
  Graph graph;
  if (!load(graph_path, graph)) return kExitInvalid;
  const std::string input_name = part_input_name(graph, input_name_arg);
  if (input_name.empty()) return kExitInvalid;
  PartRequest common;
  common.sets = o.sets;
  common.out_dir = out_dir;
  Sinks sinks;
  open_sinks(o, sinks, static_cast<int>(graph.nodes.size() * parts.size()));
  common.cache = sinks.cache.get();
  common.events = &sinks.fanout;
  say_shared_names(parts, batch_part_names(parts), out_dir);
  auto results = run_batch(graph, builtin_registry(), input_name, parts, jobs, common);
  std::vector<nlohmann::json> records;
  for (std::size_t i = 0; i < results.size(); ++i) records.push_back(part_record(results[i], parts[i], o.quiet));
  return report_batch(graph_path, records, out_dir);
}

// batch --collect DIR: waits for the Slurm batch written to DIR, then its table and summary.json.
int cmd_collect(const std::string& out_dir, bool quiet) {
  const slurm::Collected c = slurm::collect(out_dir, quiet);
  return report_batch(c.graph, c.records, out_dir, {{"slurm_job_id", c.job_id}});
}

// batch --executor slurm: the job script written and submitted, then waited for as --collect.
int cmd_batch_slurm(const std::string& graph_path, const std::vector<std::string>& parts,
                    const std::string& input_name_arg, const std::string& out_dir, const CommonOptions& o,
                    const slurm::Options& so, bool no_wait, bool dry_run) {
  Graph graph;
  if (!load(graph_path, graph)) return kExitInvalid;
  slurm::Batch b;
  b.input_name = part_input_name(graph, input_name_arg);
  if (b.input_name.empty()) return kExitInvalid;
  if (!graph.inputs.count(b.input_name)) {
    std::cerr << "error: --part-input " << b.input_name << ": the graph has no input '" << b.input_name << "'\n";
    return kExitInvalid;
  }
  try {  // a mistake in --set would fail every task: said here, before anything is submitted
    CompileOptions opt;
    opt.sets = o.sets;
    opt.require_inputs = false;
    compile(graph, builtin_registry(), opt);
  } catch (const ValidationError& e) {
    for (const auto& m : e.errors) std::cerr << "error: " << m << "\n";
    return kExitInvalid;
  }
  b.names = batch_part_names(parts);
  if (std::count(b.names.begin(), b.names.end(), "slurm")) {
    std::cerr << "error: a part named 'slurm' would write into " << (fs::path(out_dir) / "slurm").string()
              << "/, where the job's own files go; rename its file\n";
    return kExitInvalid;
  }
  say_shared_names(parts, b.names, out_dir);
  b.scallop = fs::read_symlink("/proc/self/exe").string();
  b.cwd = fs::current_path().string();
  b.graph = graph_path;
  b.parts = parts;
  b.out_dir = out_dir;
  for (const auto& set : o.sets) b.run_args.insert(b.run_args.end(), {"--set", set});
  if (o.no_cache)
    b.run_args.push_back("--no-cache");
  else  // every task the same folder, on the cluster's shared filesystem
    b.run_args.insert(b.run_args.end(), {"--cache", o.cache_dir.empty() ? DiskCache::default_dir() : o.cache_dir});
  if (o.explain) b.run_args.push_back("--explain");
  if (o.quiet) b.run_args.push_back("-q");
  const std::string script = slurm::write_job(b, so);
  if (dry_run) {
    std::cout << slurm::job_script(b, so);
    std::cerr << "not submitted; the job script is " << script << ": sbatch it, then scallop batch --collect "
              << out_dir << "\n";
    return kExitDone;
  }
  const std::string job = slurm::submit(out_dir);
  std::cerr << "submitted Slurm job " << job << ": " << parts.size() << " part(s) as array tasks 0-"
            << parts.size() - 1 << ", their logs in " << (fs::path(out_dir) / "slurm" / "logs").string() << "/\n";
  if (no_wait) {
    std::cerr << "collect the results with: scallop batch --collect " << out_dir << "\n";
    return kExitDone;
  }
  return cmd_collect(out_dir, o.quiet);
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

// What is wrong with batch's arguments together ("" when nothing): the graph, parts and -o are
// required but with --collect, which takes none of them; the Slurm options need --executor slurm.
std::string batch_arguments_error(const CLI::App& batch, const std::string& executor, const std::string& graph,
                                  const std::vector<std::string>& parts, const std::string& out,
                                  const std::string& collect) {
  if (!collect.empty())
    return graph.empty() && parts.empty() && out.empty() ? "" : "--collect DIR takes no graph, parts or -o";
  if (graph.empty() || parts.empty() || out.empty())
    return "batch needs a graph, at least one part and -o DIR (or --collect DIR)";
  const char* slurm_only[] = {"--partition", "--time", "--cpus-per-part", "--array-limit", "--no-wait", "--dry-run"};
  for (const char* name : slurm_only)
    if (executor != "slurm" && batch.count(name)) return std::string(name) + ": only with --executor slurm";
  if (executor == "slurm") {
    if (batch.count("-j")) return "-j: not with --executor slurm, where --array-limit bounds the tasks running at once";
    if (batch.count("--threads")) return "--threads: not with --executor slurm, where each part runs --cpus-per-part threads";
    if (batch.count("--events")) return "--events: not with --executor slurm; each task's progress is in DIR/slurm/logs/";
  }
  return "";
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
  std::string run_part_name, run_result;
  run->add_option("--part", run_part_name, "the part's name in messages (default: the input file's stem)");
  run->add_option("--result", run_result,
                  "FILE: write the part's record (status, certificate, errors, outputs: its line of a batch's "
                  "summary.json) as JSON; a batch's Slurm tasks hand their parts back so");
  add_common(run, run_opts);

  CommonOptions batch_opts;
  std::string batch_graph, batch_out, batch_input, batch_executor = "local", batch_collect;
  std::vector<std::string> batch_parts;
  int batch_jobs = 2;
  slurm::Options slurm_opts;
  bool batch_no_wait = false, batch_dry_run = false;
  auto* batch = app.add_subcommand("batch", "run a graph on many parts, outputs in DIR/<part stem>/ (DIR/<stem>_<extension>/ where stems clash)");
  batch->add_option("graph", batch_graph, "graph JSON file (required but with --collect)");
  batch->add_option("parts", batch_parts, "part files (required but with --collect)");
  batch->add_option("-j,--jobs", batch_jobs, "parts in flight at once")->check(CLI::Range(1, 256));
  batch->add_option("--part-input", batch_input, "graph input the parts bind to (default: the only one)");
  batch->add_option("-o,--out", batch_out, "output folder (required but with --collect)");
  add_common(batch, batch_opts);
  batch->add_option("--executor", batch_executor,
                    "local (default): the parts run here, -j at once; slurm: one Slurm job array, a task per part")
      ->check(CLI::IsMember({"local", "slurm"}));
  batch->add_option("--partition", slurm_opts.partition, "slurm: the partition (default: the cluster's)");
  batch->add_option("--time", slurm_opts.time, "slurm: time limit of each part's task, as sbatch --time takes it (30, 1:00:00)");
  batch->add_option("--cpus-per-part", slurm_opts.cpus_per_part, "slurm: cores of each part's task, and its run's threads (default 1)")
      ->check(CLI::Range(1, 1024));
  batch->add_option("--array-limit", slurm_opts.array_limit, "slurm: at most M tasks running at once (default: as the cluster allows)")
      ->check(CLI::Range(1, 1000000));
  batch->add_flag("--no-wait", batch_no_wait, "slurm: submit and return; scallop batch --collect DIR afterwards");
  batch->add_flag("--dry-run", batch_dry_run, "slurm: write DIR/slurm/job.sh and print it; submit nothing");
  batch->add_option("--collect", batch_collect, "DIR: wait for the Slurm batch in DIR to end, then its table and DIR/summary.json");

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
    if (*run) return cmd_run(run_graph, run_inputs, run_out, run_part_name, run_result, run_opts);
    if (*batch) {
      if (std::string bad = batch_arguments_error(*batch, batch_executor, batch_graph, batch_parts, batch_out,
                                                  batch_collect); !bad.empty()) {
        std::cerr << "error: " << bad << "\n";
        return kExitInvalid;
      }
      if (!batch_collect.empty()) return cmd_collect(batch_collect, batch_opts.quiet);
      if (batch_executor == "slurm")
        return cmd_batch_slurm(batch_graph, batch_parts, batch_input, batch_out, batch_opts, slurm_opts,
                               batch_no_wait, batch_dry_run);
      return cmd_batch(batch_graph, batch_parts, batch_jobs, batch_input, batch_out, batch_opts);
    }
    if (*validate) return cmd_validate(val_graph, val_sets);
    if (*nodes) return cmd_nodes(nodes_type, nodes_json, nodes_md);
    if (*dot) return cmd_dot(dot_graph);
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
