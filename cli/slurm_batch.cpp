#include "cli/slurm_batch.h"

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "engine/cache.h"

namespace scallop::slurm {
namespace fs = std::filesystem;

namespace {

// Quoted for bash only where it needs it, so that the script stays readable.
std::string shell_quote(const std::string& s) {
  const bool plain = !s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                                       "0123456789_./=:+,@%-") == std::string::npos;
  if (plain) return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs a shell command; returns its exit status (-1 when it could not run) and its stdout and
// stderr together in `output`.
int capture(const std::string& command, std::string& output) {
  output.clear();
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) output.append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n"), e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::string last_line(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line))
    if (!trimmed(line).empty()) last = trimmed(line);
  return last.size() > 300 ? last.substr(0, 300) + "..." : last;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read '" + path.string() + "'");
  return nlohmann::json::parse(in);
}

void write_json(const fs::path& path, const nlohmann::json& j) {
  const std::string tmp = temp_path_beside(path.string());
  std::ofstream(tmp) << j.dump(2) << "\n";
  fs::rename(tmp, path);
}

fs::path results_dir(const std::string& out_dir) { return fs::path(out_dir) / "slurm" / "results"; }
fs::path log_path(const std::string& out_dir, std::size_t task) {
  return fs::path(out_dir) / "slurm" / "logs" / (std::to_string(task) + ".log");
}

// Slurm's states of a task that has ended (squeue --format %T).
const std::set<std::string> kEnded = {"BOOT_FAIL",     "CANCELLED", "COMPLETED", "DEADLINE",     "FAILED", "NODE_FAIL",
                                      "OUT_OF_MEMORY", "PREEMPTED", "REVOKED",   "SPECIAL_EXIT", "TIMEOUT"};

enum class Queue { listed, gone, unknown, absent };

// Each array task's state by task id, from squeue (which keeps ended tasks for MinJobAge, 300 s
// by default; sacct would need the accounting database, which many small clusters lack). `gone`
// once Slurm has forgotten the job; `unknown` when squeue fails otherwise (`why`), `absent` when
// this host has none.
Queue poll_queue(const std::string& job, std::map<std::size_t, std::string>& state, std::string& why) {
  std::string out;
  const int rc = capture("squeue --noheader --array --states=all --jobs=" + job + " --format='%K %T'", out);
  if (rc == 127) return Queue::absent;  // the shell found no squeue
  if (rc != 0) {
    if (out.find("Invalid job id") != std::string::npos) return Queue::gone;
    why = trimmed(out).empty() ? "squeue exit status " + std::to_string(rc) : trimmed(out);
    return Queue::unknown;
  }
  std::istringstream lines(out);
  std::size_t task;
  std::string s;
  bool any = false;
  for (; lines >> task >> s; any = true) state[task] = s;
  return any ? Queue::listed : Queue::gone;
}

// The record of a part whose task left none (as part_record in main.cpp writes them).
nlohmann::json missing_record(const std::string& job, std::size_t task, const std::string& state,
                              const std::string& log) {
  std::string error = "Slurm task " + (job.empty() ? "" : job + "_") + std::to_string(task) +
                      (state.empty() ? " left no result" : " ended " + state + " without a result");
  const std::string tail = last_line(log);
  error += tail.empty() ? "; its log " + log + " is empty or missing" : "; its log " + log + " ends: " + tail;
  const auto none = nlohmann::json::array();
  return {{"ok", false},      {"certificate", "none"}, {"certificate_reasons", none}, {"seconds", 0.0},
          {"errors", {error}}, {"warnings", none},      {"outputs", none},             {"nodes_run", 0},
          {"cache_hits", 0},  {"cache_misses", 0},     {"bad_input", false},          {"verdicts", none}};
}

}  // namespace

std::string job_script(const Batch& b, const Options& o) {
  const std::string dir = b.out_dir, abs_dir = (fs::path(b.cwd) / b.out_dir).lexically_normal().string();
  std::ostringstream s;
  s << "#!/bin/bash\n"
    << "# scallop batch on Slurm, written by `scallop batch --executor slurm`.\n"
    << "#   graph  " << b.graph << "\n"
    << "#   parts  " << b.parts.size() << ", one array task each: task i runs `scallop run` on part i with the shared\n"
    << "#          cache, writes " << dir << "/<name>/ and its record " << dir << "/slurm/results/<name>.json\n"
    << "# `scallop batch --collect " << dir << "` waits for the job, then writes " << dir << "/summary.json.\n"
    << "# To run it again by hand, in " << b.cwd << ":\n"
    << "#   sbatch " << dir << "/slurm/job.sh              every part\n"
    << "#   sbatch --array=I " << dir << "/slurm/job.sh    part I alone\n"
    << "# then `scallop batch --collect " << dir << "` once the job has ended.\n"
    << "#SBATCH --job-name=scallop-" << fs::path(b.graph).stem().string() << "\n"
    << "#SBATCH --array=0-" << b.parts.size() - 1;
  if (o.array_limit > 0) s << '%' << o.array_limit;
  s << "\n"
    << "#SBATCH --cpus-per-task=" << o.cpus_per_part << "\n";
  if (!o.partition.empty()) s << "#SBATCH --partition=" << o.partition << "\n";
  if (!o.time.empty()) s << "#SBATCH --time=" << o.time << "\n";
  s << "#SBATCH --chdir=" << b.cwd << "\n"
    << "#SBATCH --output=" << abs_dir << "/slurm/logs/%a.log\n"
    << "set -eu\n"
    << "case \"$SLURM_ARRAY_TASK_ID\" in\n";
  for (std::size_t i = 0; i < b.parts.size(); ++i)
    s << "  " << i << ") part=" << shell_quote(b.parts[i]) << " name=" << shell_quote(b.names[i]) << " ;;\n";
  s << "  *) echo \"no part $SLURM_ARRAY_TASK_ID in this batch\" >&2; exit 2 ;;\n"
    << "esac\n"
    << "exec " << shell_quote(b.scallop) << " run " << shell_quote(b.graph) << " --input "
    << shell_quote(b.input_name + "=") << "\"$part\" --part \"$name\" \\\n  ";
  for (const auto& a : b.run_args) s << shell_quote(a) << " ";
  s << "--threads " << o.cpus_per_part << " \\\n"
    << "  -o " << shell_quote(dir) << "/\"$name\" --result " << shell_quote(dir) << "/slurm/results/\"$name\".json\n";
  return s.str();
}

std::string write_job(const Batch& b, const Options& o) {
  const fs::path slurm_dir = fs::path(b.out_dir) / "slurm";
  // an earlier submission's results and logs would pass for this one's
  fs::remove_all(slurm_dir / "results");
  fs::remove_all(slurm_dir / "logs");
  fs::create_directories(slurm_dir / "results");
  fs::create_directories(slurm_dir / "logs");
  const fs::path script = slurm_dir / "job.sh";
  std::ofstream(script) << job_script(b, o);
  fs::permissions(script, fs::perms::owner_exec | fs::perms::group_exec | fs::perms::others_exec, fs::perm_options::add);
  write_json(slurm_dir / "batch.json", {{"graph", b.graph},
                                        {"cwd", b.cwd},
                                        {"input_name", b.input_name},
                                        {"parts", b.parts},
                                        {"names", b.names},
                                        {"job_id", ""},
                                        {"script", script.string()}});
  return script.string();
}

std::string submit(const std::string& out_dir) {
  const fs::path batch_json = fs::path(out_dir) / "slurm" / "batch.json";
  nlohmann::json batch = read_json(batch_json);
  std::string out;
  const int rc = capture("sbatch --parsable " + shell_quote(fs::absolute(batch["script"].get<std::string>()).string()), out);
  // --parsable prints "<job id>" or "<job id>;<cluster>" on its last line, after any warnings
  std::string line, id;
  for (std::istringstream lines(out); std::getline(lines, line);)
    if (!trimmed(line).empty()) id = trimmed(line).substr(0, trimmed(line).find(';'));
  if (rc != 0 || id.empty() || id.find_first_not_of("0123456789") != std::string::npos)
    throw std::runtime_error("sbatch refused the job: " + (trimmed(out).empty() ? "exit status " + std::to_string(rc) : trimmed(out)));
  batch["job_id"] = id;
  write_json(batch_json, batch);
  return id;
}

namespace {

using Records = std::vector<std::optional<nlohmann::json>>;  // each part's record, once it is back

// Reads the records that have come back since the last call.
void read_records(const std::string& out_dir, const std::vector<std::string>& names, Records& records) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    const fs::path path = results_dir(out_dir) / (names[i] + ".json");
    if (records[i] || !fs::exists(path)) continue;
    try {
      records[i] = read_json(path);
    } catch (const std::exception&) {  // written whole or not at all: an unreadable one stays missing
    }
  }
}

// Waits until every record is back or the job has left the queue, saying how many parts are
// queued, running, done and failed whenever that changes; `state` receives each task's last state.
void wait_for_job(const std::string& job, const std::string& out_dir, const std::vector<std::string>& names,
                  bool quiet, Records& records, std::map<std::size_t, std::string>& state) {
  const bool terminal = ::isatty(STDERR_FILENO);
  std::string shown, why;
  int failures = 0, gone = 0;  // squeue's failures, and its "no such job", in a row
  for (int interval = 1;; interval = std::min(interval + 1, 10)) {
    read_records(out_dir, names, records);
    // every record back: nothing left to ask the queue (nor a squeue needed on this host)
    const bool all_back = std::all_of(records.begin(), records.end(), [](const auto& r) { return r.has_value(); });
    const Queue q = all_back ? Queue::gone : poll_queue(job, state, why);
    // A task writes its record before it ends: one the queue shows ended since the read above is
    // read again, or the last line would count it failed (seen under load: "4 done, 2 failed").
    if (!all_back) read_records(out_dir, names, records);
    failures = q == Queue::unknown ? failures + 1 : 0;
    gone = q == Queue::gone ? gone + 1 : 0;
    std::size_t queued = 0, active = 0, done = 0, failed = 0;
    for (const auto& [task, s] : state) active += !kEnded.count(s);
    for (std::size_t i = 0; i < records.size(); ++i) {
      const std::string s = state.count(i) ? state[i] : "";
      done += records[i] && (*records[i])["ok"] == true;
      failed += records[i] ? (*records[i])["ok"] == false : kEnded.count(s) > 0;  // ended without a record (yet)
      queued += !records[i] && s == "PENDING";
    }
    const std::string line = "Slurm job " + job + ": " + std::to_string(queued) + " queued, " +
                             std::to_string(records.size() - queued - done - failed) + " running, " +
                             std::to_string(done) + " done, " + std::to_string(failed) + " failed";
    if (!quiet && line != shown) std::fprintf(stderr, terminal ? "\r%s\033[K" : "%s\n", line.c_str());
    if (line != shown) interval = 1;  // something moves: look again soon
    shown = line;
    // a controller that has just restarted may not know a job for a moment: "gone" is believed
    // the third time in a row
    if (all_back || gone == 3 || (q == Queue::listed && active == 0)) break;
    if (failures == 30 || q == Queue::absent) {
      std::fprintf(stderr, "%swarning: %s; collecting what the tasks wrote so far (scallop batch --collect %s "
                           "collects again)\n",
                   terminal && !quiet ? "\n" : "",
                   q == Queue::absent ? "no squeue here" : ("squeue failed 30 times in a row: " + why).c_str(),
                   out_dir.c_str());
      break;
    }
    std::this_thread::sleep_for(std::chrono::seconds(interval));
  }
  if (terminal && !quiet) std::fprintf(stderr, "\n");
  // A task that exited wrote its record before it did; on NFS another host may not see the new
  // file for up to a minute (cached lookups, acdirmax 60 s), so such a record is waited for.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  for (;; std::this_thread::sleep_for(std::chrono::seconds(2))) {
    read_records(out_dir, names, records);
    bool waiting = false;
    for (std::size_t i = 0; i < records.size(); ++i)
      waiting |= !records[i] && state.count(i) && (state[i] == "COMPLETED" || state[i] == "FAILED");
    if (!waiting || std::chrono::steady_clock::now() > deadline) break;
  }
}

}  // namespace

Collected collect(const std::string& out_dir, bool quiet) {
  const fs::path batch_json = fs::path(out_dir) / "slurm" / "batch.json";
  if (!fs::exists(batch_json))
    throw std::runtime_error("no Slurm batch in '" + out_dir + "': " + batch_json.string() +
                             " is missing (scallop batch --executor slurm -o " + out_dir + " writes it)");
  const nlohmann::json batch = read_json(batch_json);
  const std::vector<std::string> parts = batch["parts"], names = batch["names"];
  Collected c;
  c.graph = batch["graph"];
  c.job_id = batch["job_id"];
  Records records(parts.size());
  std::map<std::size_t, std::string> state;  // the last state Slurm gave each task
  if (!c.job_id.empty())
    wait_for_job(c.job_id, out_dir, names, quiet, records, state);
  else  // written with --dry-run and submitted by hand, if at all: what is there
    read_records(out_dir, names, records);
  for (std::size_t i = 0; i < parts.size(); ++i) {
    const std::string log = log_path(out_dir, i).string();
    nlohmann::json r = records[i] ? *records[i] : missing_record(c.job_id, i, state.count(i) ? state[i] : "", log);
    r["part"] = names[i];
    r["input"] = parts[i];
    r["slurm_job_id"] = c.job_id;
    r["slurm_task_id"] = i;
    r["slurm_log"] = log;
    c.records.push_back(std::move(r));
  }
  return c;
}

}  // namespace scallop::slurm
