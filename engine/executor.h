// Runs a Plan on oneTBB: independent branches run concurrently, nodes use parallel_for inside.
//
// A failing node reports node id, type and part; its dependents are skipped; independent
// branches still finish. Outputs live in memory until their last consumer has run (graph
// outputs are kept), and in the disk cache when one is given.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/cache.h"
#include "engine/events.h"
#include "engine/graph.h"

namespace scallop {

struct RunOptions {
  std::string part;               // name of the part (input file stem) for messages
  DiskCache* cache = nullptr;     // null: no disk cache
  EventSink* events = nullptr;    // null: silent
  std::string out_dir;            // where nodes write files of their own ("" : working directory)
};

struct NodeRun {
  std::string id, type;
  std::string status;  // ok | cached | failed | skipped
  std::string cache;   // hit | miss | off
  std::string why;     // why the cache hit or missed, or why the node was skipped
  std::string error;
  bool bad_input = false;  // failed with InputError: an input file is unreadable or malformed
  std::vector<std::string> warnings;  // what the node said with ctx.warn (replayed on a cache hit)
  std::string key;
  double start = 0, finish = 0;  // seconds since process start
  double seconds() const { return finish - start; }
  // The process's resident-memory peak while the node ran (MiB; 0 when unknown). Nodes running at
  // the same time share it: with one node at a time (--threads 1) it is the node's own.
  double peak_mib = 0;
};

struct RunResult {
  std::map<std::string, ValuePtr> outputs;  // graph outputs that were produced
  std::vector<NodeRun> nodes;               // in plan order
  std::vector<std::string> errors;          // "node 'id' (type) failed on part 'p': message"
  bool ok() const { return errors.empty(); }
  // Failed, and only because input files are unreadable or malformed (every failed node says so).
  bool only_bad_input() const;
  int executed() const;                     // nodes that actually ran (not cached, not skipped)
  const NodeRun* find(const std::string& id) const;
};

RunResult execute(const Plan& plan, const Registry& registry, const std::map<std::string, ValuePtr>& inputs,
                  const RunOptions& options = {});

}  // namespace scallop
