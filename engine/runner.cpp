#include "engine/runner.h"

#include <map>
#include <set>

#include <tbb/task_group.h>

#include <atomic>
#include <filesystem>

#include "engine/file_ref.h"

namespace scallop {
namespace fs = std::filesystem;

std::string default_input_path(const Graph& graph, const std::string& name) {
  auto it = graph.inputs.find(name);
  if (it == graph.inputs.end() || it->second.default_path.empty()) return "";
  fs::path p(it->second.default_path);
  if (p.is_absolute() || graph.path.empty()) return p.string();
  return (fs::path(graph.path).parent_path() / p).lexically_normal().string();
}

PartResult run_part(const Graph& graph, const Registry& registry, const PartRequest& req) {
  PartResult r;
  double t0 = seconds_since_start();
  std::map<std::string, std::string> paths = req.inputs;
  for (const auto& [name, in] : graph.inputs)
    if (!paths.count(name) && !in.default_path.empty()) paths[name] = default_input_path(graph, name);
  r.part = req.part;
  if (r.part.empty() && !paths.empty()) r.part = fs::path(paths.begin()->second).stem().string();

  Plan plan;
  try {
    CompileOptions opt;
    opt.sets = req.sets;
    for (const auto& [name, path] : req.inputs) opt.provided_inputs.insert(name);  // defaults are checked
    plan = compile(graph, registry, opt);
  } catch (const ValidationError& e) {
    r.errors = e.errors;
    r.bad_input = true;
    r.seconds = seconds_since_start() - t0;
    return r;
  }
  std::map<std::string, ValuePtr> values;
  for (const auto& [name, path] : paths) {
    if (!graph.inputs.count(name)) {
      r.errors.push_back("--input " + name + ": unknown graph input '" + name + "'");
      continue;
    }
    try {
      values[name] = std::make_shared<FileRef>(FileRef::open(path));
    } catch (const std::exception& e) {
      r.errors.push_back("input '" + name + "': " + e.what());
    }
  }
  if (!r.errors.empty()) {
    r.bad_input = true;
    r.seconds = seconds_since_start() - t0;
    return r;
  }
  RunOptions ro;
  ro.part = r.part;
  ro.cache = req.cache;
  ro.events = req.events;
  ro.out_dir = req.out_dir;
  r.run = execute(plan, registry, values, ro);
  r.errors = r.run.errors;
  r.bad_input = r.run.only_bad_input();
  if (!req.out_dir.empty()) {
    try {
      fs::create_directories(req.out_dir);
      for (const auto& [name, value] : r.run.outputs) {
        const ValueType* vt = registry.values().find(value->type_name());
        std::string ext = vt ? vt->extension : "bin";
        std::string path = (fs::path(req.out_dir) / (name + "." + ext)).string();
        value->write_file(path);
        r.written.push_back(path);
      }
    } catch (const std::exception& e) {
      r.errors.push_back(std::string("writing outputs: ") + e.what());
      r.bad_input = false;
    }
  }
  r.ok = r.errors.empty();
  r.seconds = seconds_since_start() - t0;
  return r;
}

std::vector<std::string> batch_part_names(const std::vector<std::string>& parts) {
  std::map<std::string, std::vector<std::size_t>> by_stem;
  for (std::size_t i = 0; i < parts.size(); ++i) by_stem[fs::path(parts[i]).stem().string()].push_back(i);
  std::vector<std::string> names(parts.size());
  std::set<std::string> used;
  for (const auto& [stem, group] : by_stem)
    if (group.size() == 1) used.insert(names[group[0]] = stem);
  for (const auto& [stem, group] : by_stem) {
    if (group.size() == 1) continue;
    for (std::size_t i : group) {
      const std::string ext = fs::path(parts[i]).extension().string();
      const std::string base = ext.size() > 1 ? stem + "_" + ext.substr(1) : stem;
      std::string name = base;
      for (int n = 2; used.count(name); ++n) name = base + "_" + std::to_string(n);
      used.insert(names[i] = name);
    }
  }
  return names;
}

std::vector<PartResult> run_batch(const Graph& graph, const Registry& registry, const std::string& input_name,
                                  const std::vector<std::string>& parts, int jobs, const PartRequest& common) {
  std::vector<PartResult> results(parts.size());
  const std::vector<std::string> names = batch_part_names(parts);
  std::atomic<std::size_t> next{0};
  tbb::task_group group;
  // `jobs` workers pull parts one at a time: at most `jobs` parts are in flight.
  for (int w = 0; w < std::max(1, jobs); ++w)
    group.run([&] {
      for (std::size_t i; (i = next++) < parts.size();) {
        PartRequest req = common;
        req.inputs[input_name] = parts[i];
        req.part = names[i];
        if (!common.out_dir.empty()) req.out_dir = (fs::path(common.out_dir) / req.part).string();
        try {
          results[i] = run_part(graph, registry, req);
        } catch (const std::exception& e) {  // run_part does not throw; belt and braces
          results[i].part = req.part;
          results[i].errors = {e.what()};
        }
      }
    });
  group.wait();
  return results;
}

}  // namespace scallop
