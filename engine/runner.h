// Running a graph on one part (input files in, output files out) and on many parts in a batch.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "engine/executor.h"

namespace scallop {

struct PartRequest {
  std::map<std::string, std::string> inputs;  // graph input name -> file path
  std::vector<std::string> sets;              // --set NAME=VALUE
  std::string out_dir;                        // "" : do not write outputs
  std::string part;                           // name for messages; default: stem of the first input
  DiskCache* cache = nullptr;
  EventSink* events = nullptr;
};

struct PartResult {
  std::string part;
  bool ok = false;
  std::vector<std::string> errors;   // validation, input and node errors
  // The errors are all about bad input: an invalid graph or --set, a missing input file, or one
  // a node could not read (InputError). `scallop` exits 2 for these, 1 for other failures.
  bool bad_input = false;
  std::vector<std::string> written;  // output files
  RunResult run;
  double seconds = 0;
};

// Validates, opens the inputs, executes and writes each graph output as
// <out_dir>/<output name>.<extension of its type>. Never throws: every problem lands in errors.
PartResult run_part(const Graph& graph, const Registry& registry, const PartRequest& request);

// The name (and output folder) of each batch part: its file's stem, or, where stems clash
// (good.ply, good.xyz), stem_extension (good_ply, good_xyz), numbered on when even those clash
// (a/good.ply, b/good.ply: good_ply, good_ply_2).
std::vector<std::string> batch_part_names(const std::vector<std::string>& parts);

// Runs every part file through the graph (bound to graph input `input_name`), at most `jobs`
// parts in flight, outputs in <out_dir>/<batch_part_names>/. One part's failure never stops the
// others.
std::vector<PartResult> run_batch(const Graph& graph, const Registry& registry, const std::string& input_name,
                                  const std::vector<std::string>& parts, int jobs, const PartRequest& common);

// The path a graph input's default file resolves to (relative to the graph file's folder).
std::string default_input_path(const Graph& graph, const std::string& name);

}  // namespace scallop
