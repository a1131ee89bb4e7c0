#include "engine/executor.h"

#include <tbb/task_group.h>

#include <atomic>
#include <mutex>
#include <set>

#include "engine/hash.h"
#include "engine/memory.h"

namespace scallop {

int RunResult::executed() const {
  int n = 0;
  for (const auto& r : nodes) n += (r.status == "ok" || r.status == "failed");
  return n;
}

bool RunResult::only_bad_input() const {
  if (ok()) return false;
  for (const auto& r : nodes)
    if (r.status == "failed" && !r.bad_input) return false;
  return true;
}

const NodeRun* RunResult::find(const std::string& id) const {
  for (const auto& r : nodes)
    if (r.id == id) return &r;
  return nullptr;
}

namespace {

using json = nlohmann::json;

// Says what changed since the last recorded run of this node, for --explain.
std::string explain_miss(const std::optional<json>& last, const json& now) {
  if (!last) return "no earlier run recorded";
  if (last->value("key", "") == now["key"]) return "entry missing";
  const json formats = last->value("formats", json::object());
  for (const auto& [type, format] : now["formats"].items())
    if (!formats.contains(type) || formats[type] != format)
      return "the cache format of value type " + type + " changed (" +
             (formats.contains(type) ? formats[type].dump() : "unset") + " -> " + format.dump() + ")";
  if (last->value("version", 0) != now["version"])
    return "node version changed (" + std::to_string(last->value("version", 0)) + " -> " +
           now["version"].dump() + ")";
  std::string why;
  const json& lp = (*last)["params"];
  for (const auto& [k, v] : now["params"].items())
    if (!lp.contains(k) || lp[k] != v)
      why += (why.empty() ? "" : ", ") + std::string("parameter ") + k + " changed (" +
             (lp.contains(k) ? lp[k].dump() : "unset") + " -> " + v.dump() + ")";
  const json& li = (*last)["inputs"];
  for (const auto& [k, v] : now["inputs"].items())
    if (!li.contains(k) || li[k] != v) why += (why.empty() ? "" : ", ") + std::string("input ") + k + " changed";
  return why.empty() ? "key changed" : why;
}

// The format version of each value type the node reads or writes, by name: a new layout of one
// type invalidates the entries of the nodes that use it and of no others.
json value_formats(const NodeDecl& decl, const ValueTypes& types) {
  json formats = json::object();
  for (const auto* ports : {&decl.inputs, &decl.outputs})
    for (const PortDecl& p : *ports)
      if (const ValueType* t = types.find(p.type)) formats[p.type] = t->format;
  return formats;
}

// Where a cache entry's warnings are kept (beside the manifests, by the entry's key): a node's
// output depends only on its key, so the warnings it gave with it do too.
std::string warnings_identity(const std::string& key) { return "warnings#" + key; }

}  // namespace

RunResult execute(const Plan& plan, const Registry& registry, const std::map<std::string, ValuePtr>& inputs,
                  const RunOptions& options) {
  const int n = static_cast<int>(plan.nodes.size());
  RunResult result;
  result.nodes.resize(n);
  std::vector<std::map<std::string, ValuePtr>> outputs(n);
  std::vector<std::string> keys(n);
  std::vector<std::atomic<int>> pending(n), consumers_left(n);
  std::vector<std::atomic<bool>> good(n);  // produced its outputs
  std::vector<bool> is_graph_output(n, false);
  for (const auto& [name, src] : plan.outputs) is_graph_output[src.node] = true;
  for (int i = 0; i < n; ++i) {
    pending[i] = static_cast<int>(plan.nodes[i].deps.size());
    consumers_left[i] = static_cast<int>(plan.nodes[i].dependents.size());
    good[i] = false;
  }
  std::mutex output_mutex, error_mutex;
  auto emit = [&](json e) {
    if (!options.events) return;
    e["t"] = seconds_since_start();
    e["part"] = options.part;
    options.events->on_event(e);
  };
  std::map<std::string, std::string> input_keys;
  for (const auto& [name, value] : inputs) input_keys[name] = value ? value->content_key() : "";

  // Keys first (a Merkle chain needs no values), then which nodes must be materialised: graph
  // outputs, sinks (side effects), and the inputs of every node that has to run. A cached node
  // nothing downstream needs is never even loaded.
  std::vector<json> manifests(n);
  for (int i : plan.order) {
    const PlanNode& pn = plan.nodes[i];
    json m{{"type", pn.decl->type},
           {"version", pn.decl->version},
           {"formats", value_formats(*pn.decl, registry.values())},
           {"params", pn.params},
           {"inputs", json::object()}};
    for (const auto& [port, src] : pn.inputs)
      m["inputs"][port] = src.node < 0 ? input_keys[src.port] : hash_bytes(keys[src.node] + "." + src.port);
    keys[i] = hash_bytes(m.dump());
    m["key"] = keys[i];
    manifests[i] = std::move(m);
  }
  // What each node does, decided before anything runs:
  //  have    a sound entry is on disk (header, key and checksum checked; a bad one is deleted);
  //  runs    computed: it has no sound entry, and something needs its outputs or it is cached on
  //          disk (the cache heals: an entry that went missing or bad is written again, even when
  //          its consumers all came from the cache);
  //  needed  its outputs must be in memory: graph outputs, sinks (side effects), and the inputs of
  //          every node that runs, however far up a missing entry reaches. A cached node nothing
  //          needs is never even loaded.
  std::vector<char> have(n, 0), runs(n, 0), needed(n, 0);
  std::vector<std::string> bad_entry(n);  // why a node's entry was rejected ("" if none or missing)
  if (options.cache)
    for (int i = 0; i < n; ++i)
      if (plan.nodes[i].decl->cache_on_disk) {
        DiskCache::Check c = options.cache->check(keys[i]);
        have[i] = c.sound;
        if (!c.sound && c.why != "no entry") bad_entry[i] = c.why;
      }
  for (auto it = plan.order.rbegin(); it != plan.order.rend(); ++it) {
    int i = *it;
    needed[i] = is_graph_output[i] || plan.nodes[i].dependents.empty();
    for (int d : plan.nodes[i].dependents) needed[i] |= runs[d];
    const bool heal = options.cache && plan.nodes[i].decl->cache_on_disk;
    runs[i] = !have[i] && (needed[i] || heal);
  }

  // Which outputs of a node must be decoded from its entry: the graph's outputs and what the
  // nodes that run read.
  std::vector<std::set<std::string>> wanted_ports(n);
  for (const auto& [name, src] : plan.outputs) wanted_ports[src.node].insert(src.port);
  for (int i = 0; i < n; ++i)
    if (runs[i])
      for (const auto& [port, src] : plan.nodes[i].inputs)
        if (src.node >= 0) wanted_ports[src.node].insert(src.port);

  // The memory high-water mark restarts whenever a node starts with no other running, so each
  // node's peak is its own when nodes run one at a time.
  std::atomic<int> running{0};
  tbb::task_group stores;  // cache entries being written
  auto run_node = [&](int i) {
    const PlanNode& pn = plan.nodes[i];
    NodeRun& rec = result.nodes[i];
    if (running++ == 0) reset_peak_resident();
    rec.id = pn.id;
    rec.type = pn.decl->type;
    rec.key = keys[i];
    rec.start = seconds_since_start();
    emit({{"event", "node_start"}, {"node", pn.id}, {"type", rec.type}});

    std::map<std::string, ValuePtr> in;
    std::string skipped_because;
    if (runs[i]) {
      std::lock_guard lock(output_mutex);
      for (const auto& [port, src] : pn.inputs) {
        if (src.node < 0) {
          auto found = inputs.find(src.port);
          in[port] = found == inputs.end() ? nullptr : found->second;
        } else if (!good[src.node]) {
          skipped_because = "input from '" + plan.nodes[src.node].id + "' is missing";
        } else {
          in[port] = outputs[src.node][src.port];
        }
      }
    }

    std::map<std::string, ValuePtr> out;
    std::string identity = plan.graph_path + "#" + plan.graph_name + "#" + pn.id;
    rec.cache = options.cache && pn.decl->cache_on_disk ? "miss" : "off";
    if (!skipped_because.empty()) {
      rec.status = "skipped";
      rec.why = skipped_because;
    } else if (have[i]) {
      // the warnings of the run that made the entry: a cached result is as suspect as a fresh one
      if (auto said = options.cache->last_manifest(warnings_identity(keys[i])))
        for (const auto& m : said->value("warnings", json::array())) {
          rec.warnings.push_back(m.get<std::string>());
          emit({{"event", "node_warning"}, {"node", pn.id}, {"type", rec.type}, {"message", rec.warnings.back()},
                {"cached", true}});
        }
      rec.status = "cached";
      rec.cache = "hit";
      rec.why = "same type, version, parameters and inputs";
      if (needed[i]) {
        auto hit = options.cache->load(keys[i], registry.values(), &wanted_ports[i]);
        if (hit.hit) {
          out = std::move(hit.outputs);
        } else {  // the entry went bad after it was checked: its inputs were never loaded
          rec.status = "failed";
          rec.error = "its cache entry went bad during the run: " + hit.why + "; run again to recompute it";
        }
      } else {
        rec.why += " (not loaded: nothing downstream needs it)";
      }
    } else if (!runs[i]) {  // not cached on disk, and every consumer came from the cache
      rec.status = "skipped";
      rec.why = "not run: nothing downstream needs it";
    } else {
      if (options.cache && !pn.decl->cache_on_disk) rec.why = "this node is not cached on disk";
      else if (options.cache && !bad_entry[i].empty()) rec.why = bad_entry[i];
      else if (options.cache) rec.why = explain_miss(options.cache->last_manifest(identity), manifests[i]);
      if (options.cache && !needed[i]) rec.why += "; recomputed so that the cache holds it again";
      try {
        double last_emit = -1;
        std::mutex warn_mutex;
        NodeContext ctx(
            *pn.decl, pn.id, options.part, pn.params, in,
            [&](double f, const std::string& msg) {
              if (f - last_emit < 0.01 && f < 1.0) return;
              last_emit = f;
              emit({{"event", "node_progress"}, {"node", pn.id}, {"type", rec.type}, {"fraction", f}, {"message", msg}});
            },
            [&](const std::string& msg) {
              {
                std::lock_guard lock(warn_mutex);
                rec.warnings.push_back(msg);
              }
              emit({{"event", "node_warning"}, {"node", pn.id}, {"type", rec.type}, {"message", msg}});
            });
        ctx.set_output_dir(options.out_dir);
        pn.decl->run(ctx);
        out = ctx.take_outputs();
        for (const auto& od : pn.decl->outputs)
          if (!out.count(od.name) || !out[od.name])
            throw std::logic_error("node did not produce its output '" + od.name + "'");
        rec.status = "ok";
        // The entry is written beside the nodes that follow, not before them (at a million
        // points cloud.trim_steep's 206 MiB entry held its successors 0.8 s: serialised, hashed
        // and synced to disk before it is renamed into place).
        if (options.cache && pn.decl->cache_on_disk)
          stores.run([&, i, out, identity] {
            NodeRun& done = result.nodes[i];
            try {
              options.cache->store(keys[i], out);
              options.cache->write_manifest(identity, manifests[i]);
              if (!done.warnings.empty())
                options.cache->write_manifest(warnings_identity(keys[i]), json{{"warnings", done.warnings}});
            } catch (const std::exception& e) {
              // The outputs are sound; only a later run loses them.
              const std::string msg = std::string("its result could not be kept in the cache: ") + e.what();
              {
                std::lock_guard lock(error_mutex);
                done.warnings.push_back(msg);
              }
              emit({{"event", "node_warning"}, {"node", done.id}, {"type", done.type}, {"message", msg}});
            }
          });
      } catch (const InputError& e) {
        rec.status = "failed";
        rec.error = e.what();
        rec.bad_input = true;
      } catch (const std::exception& e) {
        rec.status = "failed";
        rec.error = e.what();
      }
    }
    if (rec.status == "failed" && !pn.set_by.empty()) {
      // The command line may be the cause: say which of its --set values this node was given.
      std::string sets;
      for (const auto& [param, set] : pn.set_by) sets += (sets.empty() ? "" : ", ") + set;
      rec.error += " (given " + sets + ")";
    }
    if (rec.status == "failed") {
      std::lock_guard lock(error_mutex);
      result.errors.push_back("node '" + pn.id + "' (" + rec.type + ") failed" +
                              (options.part.empty() ? "" : " on part '" + options.part + "'") + ": " + rec.error);
    } else if (rec.status != "skipped") {
      std::lock_guard lock(output_mutex);
      outputs[i] = std::move(out);
      good[i] = true;
    }
    rec.finish = seconds_since_start();
    rec.peak_mib = static_cast<double>(peak_resident_bytes()) / (1024.0 * 1024.0);
    --running;
    emit({{"event", "node_finish"}, {"node", pn.id}, {"type", rec.type}, {"status", rec.status},
          {"seconds", rec.seconds()}, {"peak_mib", rec.peak_mib}, {"cache", rec.cache}, {"why", rec.why},
          {"error", rec.error}, {"key", rec.key}});

    // Memory tier: free each input's producer once its last consumer is done.
    std::lock_guard lock(output_mutex);
    for (int d : pn.deps)
      if (--consumers_left[d] == 0 && !is_graph_output[d]) outputs[d].clear();
  };

  // A node with a sound entry reads no inputs: it loads at once, beside the others, instead of
  // after its producers (a rerun at a million points loaded its entries one after another, 1 s,
  // most of it the first touch of fresh memory).
  tbb::task_group group;
  std::function<void(int)> launch = [&](int i) {
    group.run([&, i] {
      run_node(i);
      for (int d : plan.nodes[i].dependents)
        if (--pending[d] == 0 && !have[d]) launch(d);
    });
  };
  emit({{"event", "run_start"}, {"nodes", n}});
  for (int i = 0; i < n; ++i)
    if (plan.nodes[i].deps.empty() || have[i]) launch(i);
  group.wait();
  stores.wait();

  for (const auto& [name, src] : plan.outputs)
    if (good[src.node]) {
      auto it = outputs[src.node].find(src.port);
      if (it != outputs[src.node].end()) result.outputs[name] = it->second;
    }
  emit({{"event", "run_finish"}, {"ok", result.ok()}, {"errors", result.errors}});
  return result;
}

}  // namespace scallop
