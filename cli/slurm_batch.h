// `scallop batch --executor slurm`: the parts of a batch as one Slurm job array.
//
// scallop does not schedule: a run of one part is a pure, content-addressed function of graph,
// parameters and input, so each array task runs `scallop run` on its part with the shared cache,
// and hands back its part's record (the line of summary.json) as a file. Everything the batch
// needs afterwards lies in DIR/slurm/, so `scallop batch --collect DIR` can finish a batch from
// those files alone, on any host that sees DIR:
//
//   DIR/slurm/job.sh                the job script (readable; `sbatch` it again by hand)
//   DIR/slurm/batch.json            graph, parts, their names, job id: what --collect reads
//   DIR/slurm/logs/<task>.log       each task's stdout and stderr
//   DIR/slurm/results/<part>.json   each part's record, written by `scallop run --result`
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace scallop::slurm {

// What is asked of Slurm (the batch options --partition, --time, --cpus-per-part, --array-limit).
struct Options {
  std::string partition;  // "" : the cluster's default partition
  std::string time;       // "" : the partition's default time limit; else as sbatch --time takes it
  int cpus_per_part = 1;  // sbatch --cpus-per-task, and `scallop run --threads`
  int array_limit = 0;    // at most this many tasks running at once (sbatch --array=...%M); 0: no limit
};

// What each task runs. Paths are as the user gave them, relative to `cwd`, which is the job's
// working directory (--chdir), so the outputs and the summary name them as a local batch does.
struct Batch {
  std::string scallop;                // absolute path of the scallop command the tasks run
  std::string cwd;                    // absolute
  std::string graph;
  std::string input_name;             // the graph input each part binds to
  std::vector<std::string> parts;     // part files
  std::vector<std::string> names;     // batch_part_names(parts): output folder and name of each
  std::vector<std::string> run_args;  // passed to every `scallop run`: --set, --cache or --no-cache, -q, ...
  std::string out_dir;
};

// The job script: one array task per part, task i running `scallop run` on part i.
std::string job_script(const Batch& batch, const Options& options);

// Writes DIR/slurm/job.sh and DIR/slurm/batch.json, clearing the logs and results of an earlier
// submission; returns the script's path.
std::string write_job(const Batch& batch, const Options& options);

// Submits DIR/slurm/job.sh with sbatch and records the job id in batch.json; returns the id.
// Throws std::runtime_error with sbatch's own message when it refuses.
std::string submit(const std::string& out_dir);

struct Collected {
  std::string graph;   // as batch.json holds it
  std::string job_id;  // "" when scallop did not submit the job (written with --dry-run)
  std::vector<nlohmann::json> records;  // one per part, in the parts' order
};

// Waits until the job of DIR/slurm/batch.json has left Slurm's queue, saying on stderr how many
// parts are queued, running, done and failed (unless quiet), then reads each part's record. A
// task that left none (killed at its time limit, out of memory, its node lost) gets a failed
// record saying how it ended and the end of its log. Throws std::runtime_error when DIR holds no
// Slurm batch.
Collected collect(const std::string& out_dir, bool quiet);

}  // namespace scallop::slurm
