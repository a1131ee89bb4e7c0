// `scallop batch --executor slurm` on a real one-node Slurm cluster started for the test: munged,
// slurmctld and slurmd with a minimal slurm.conf naming localhost, all in a temp folder, stopped
// at the end even when the test fails. Where the daemons cannot start, the test says why and is
// skipped; with SCALLOP_REQUIRE_SLURM=1 (CI, .ci/run) it fails instead.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "tests/test_support.h"

namespace scallop {
namespace {
namespace fs = std::filesystem;

const std::string kScallop = SCALLOP_BINARY;
const std::string kZigzag = std::string(SCALLOP_SOURCE_DIR) + "/graphs/isoparametric-zigzag.json";

std::string tail(const fs::path& log, std::size_t lines = 5) {
  std::ifstream in(log);
  std::vector<std::string> all;
  for (std::string line; std::getline(in, line);) all.push_back(line);
  std::string t;
  for (std::size_t i = all.size() > lines ? all.size() - lines : 0; i < all.size(); ++i) t += "\n  " + all[i];
  return t.empty() ? " (its log " + log.string() + " is empty)" : t;
}

// A TCP port nothing listens on now.
int free_port() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  socklen_t len = sizeof a;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

// munged, slurmctld and slurmd of a one-node cluster in `dir`, each a child of this process in
// the foreground, so that they die with it even when it is killed (PR_SET_PDEATHSIG).
class LocalSlurm {
 public:
  explicit LocalSlurm(const fs::path& dir) : dir_(dir) {
    for (const char* tool : {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo"})
      if (test::run_command(std::string("command -v ") + tool) != 0) {
        why = std::string(tool) + " is not on PATH (scripts/install-deps.sh installs slurm-wlm and munge)";
        return;
      }
    const passwd* pw = ::getpwuid(::getuid());
    user_ = pw ? pw->pw_name : "root";
    fs::create_directories(dir / "state");
    fs::create_directories(dir / "spool");
    // munged wants its socket's folder open to all and its key readable by its user alone
    fs::permissions(dir, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);
    std::string key(1024, '\0');
    std::ifstream("/dev/urandom", std::ios::binary).read(key.data(), key.size());
    test::write_file(dir / "munge.key", key);
    fs::permissions(dir / "munge.key", fs::perms::owner_read);
    const std::string socket = (dir / "munge.socket").string();
    const std::string p = dir.string() + "/";
    std::ostringstream conf;
    conf << "ClusterName=scallop-test\nSlurmctldHost=localhost\n"
         << "SlurmctldPort=" << free_port() << "\nSlurmdPort=" << free_port() << "\n"
         << "SlurmUser=" << user_ << "\nSlurmdUser=" << user_ << "\n"
         << "AuthType=auth/munge\nAuthInfo=socket=" << socket << "\nCredType=cred/munge\n"
         << "StateSaveLocation=" << p << "state\nSlurmdSpoolDir=" << p << "spool\n"
         << "SlurmctldPidFile=" << p << "slurmctld.pid\nSlurmdPidFile=" << p << "slurmd.pid\n"
         << "SlurmctldLogFile=" << p << "slurmctld.log\nSlurmdLogFile=" << p << "slurmd.log\n"
         // no cgroups, no accounting database: what a container or a bare machine has
         << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\nJobAcctGatherType=jobacct_gather/none\n"
         << "AccountingStorageType=accounting_storage/none\nMpiDefault=none\n"
         << "SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\nReturnToService=2\n"
         << "SlurmdParameters=config_overrides\n"
         << "NodeName=localhost NodeAddr=127.0.0.1 CPUs=" << std::max(1u, std::thread::hardware_concurrency())
         << " State=UNKNOWN\n"
         << "PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n";
    conf_ = (dir / "slurm.conf").string();
    test::write_file(conf_, conf.str());

    start({"munged", "--foreground", "--force", "--key-file=" + p + "munge.key", "--socket=" + socket,
           "--pid-file=" + p + "munged.pid", "--log-file=" + p + "munged.log", "--seed-file=" + p + "munged.seed"},
          "munged.out");
    if (!wait_for([&] { return fs::exists(socket); }, 10, "munged", dir / "munged.log")) return;
    start({"slurmctld", "-D", "-f", conf_}, "slurmctld.out");
    start({"slurmd", "-D", "-f", conf_, "-N", "localhost"}, "slurmd.out");
    std::string state;
    wait_for(
        [&] {
          test::run_command(env() + " sinfo --noheader --Node --format=%T", &state);
          return state.rfind("idle", 0) == 0;
        },
        30, "the node", dir / "slurmd.log");
    if (!why.empty()) why += "\n  sinfo says: " + state + "  slurmctld's log:" + tail(dir / "slurmctld.log");
  }

  ~LocalSlurm() {
    if (!conf_.empty()) test::run_command(env() + " scancel --user=" + user_);
    for (auto it = daemons_.rbegin(); it != daemons_.rend(); ++it) {
      ::kill(it->first, SIGTERM);
      int status = 0;
      for (int i = 0; i < 100 && ::waitpid(it->first, &status, WNOHANG) == 0; ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (::waitpid(it->first, &status, WNOHANG) == 0) {
        ::kill(it->first, SIGKILL);
        ::waitpid(it->first, &status, 0);
      }
    }
  }

  std::string why;  // "" when the cluster is up, else what went wrong
  std::string env() const { return "SLURM_CONF=" + conf_; }

 private:
  void start(const std::vector<std::string>& args, const std::string& log) {
    std::vector<char*> argv;
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const std::string out = (dir_ / log).string();
    const pid_t parent = ::getpid();
    pid_t pid = ::fork();
    if (pid == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) ::_exit(1);
      int fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      ::execvp(argv[0], argv.data());
      ::_exit(127);
    }
    if (pid > 0) daemons_.emplace_back(pid, args[0]);
  }

  // Waits up to `seconds` for `ready`; else sets `why`, naming whichever daemon exited.
  template <class F>
  bool wait_for(F ready, int seconds, const std::string& what, const fs::path& log) {
    for (int i = 0; i < seconds * 5; ++i) {
      if (ready()) return true;
      for (const auto& [pid, name] : daemons_)
        if (int status = 0; ::waitpid(pid, &status, WNOHANG) == pid) {
          why = name + " exited at start (status " + std::to_string(status) + "):" + tail(dir_ / (name + ".out")) +
                tail(dir_ / (name + ".log"));
          return false;
        }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    why = what + " was not ready after " + std::to_string(seconds) + " s:" + tail(log);
    return false;
  }

  fs::path dir_;
  std::string conf_, user_;
  std::vector<std::pair<pid_t, std::string>> daemons_;
};

// A small wavy patch (n x n points 0.5 mm apart) as ASCII PLY: about a second through the
// zig-zag graph.
void write_wavy_patch(const fs::path& path, int n, double phase) {
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex " << n * n
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double x = i * 0.5, y = j * 0.5 + 0.01 * std::sin(i);
      ply << x << " " << y << " " << 0.8 * std::sin(x / 5 + phase) + 0.5 * std::cos(y / 6) << "\n";
    }
  test::write_file(path, ply.str());
}

// Every file under `dir` but summary.json and the Slurm job's own folder, by path below `dir`.
std::map<std::string, std::string> output_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& f : fs::recursive_directory_iterator(dir)) {
    const std::string rel = fs::relative(f.path(), dir).string();
    if (f.is_regular_file() && rel != "summary.json" && rel.rfind("slurm/", 0) != 0)
      files[rel] = test::read_file(f.path());
  }
  return files;
}

// What a summary says of each part, but for timings, output paths and cache counts.
nlohmann::json verdicts(const nlohmann::json& summary) {
  nlohmann::json v = nlohmann::json::array();
  for (const auto& p : summary["parts"])
    v.push_back({p["part"], p["input"], p["ok"], p["certificate"], p["certificate_reasons"], p["errors"], p["warnings"]});
  return v;
}

TEST(Slurm, BatchAsAJobArrayMatchesTheLocalBatchAndASecondSubmissionIsAllCacheHits) {
  test::TempDir dir;
  LocalSlurm slurm(dir.path / "cluster");
  if (!slurm.why.empty()) {
    if (std::getenv("SCALLOP_REQUIRE_SLURM")) FAIL() << "the Slurm cluster did not start: " << slurm.why;
    GTEST_SKIP() << "the Slurm cluster did not start: " << slurm.why;
  }
  std::string parts;  // six parts, the third a broken file
  for (int k = 0; k < 5; ++k) {
    write_wavy_patch(dir.path / ("patch" + std::to_string(k) + ".ply"), 26 + 2 * k, k);
    parts += " patch" + std::to_string(k) + ".ply" + (k == 1 ? " broken.ply" : "");
  }
  test::write_file(dir.path / "broken.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n");
  const std::string cd = "cd " + dir.str() + " && ";
  std::string out;
  // exit status 2: a part failed, and only on its bad input
  ASSERT_EQ(test::run_command(cd + kScallop + " batch " + kZigzag + parts + " -j 2 --no-cache -q -o local", &out), 2) << out;
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_EQ(test::run_command(cd + slurm.env() + " " + kScallop + " batch " + kZigzag + parts +
                                  " --executor slurm --cache cache -o cluster_out", &out), 2) << out;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_NE(out.find("submitted Slurm job "), std::string::npos) << out;
  EXPECT_NE(out.find(": 0 queued, 0 running, 5 done, 1 failed\n"), std::string::npos) << out;  // the last progress line
  EXPECT_NE(out.find("5 of 6 parts ok, 0 certificate(s) failed; summary in cluster_out/summary.json"), std::string::npos) << out;
  EXPECT_NE(out.find("error: 1 part(s) failed: broken"), std::string::npos) << out;

  // the same files, byte for byte (no output holds a timing)
  const auto local = output_files(dir.path / "local");
  ASSERT_EQ(local.size(), 5u * 12u);
  EXPECT_TRUE(local == output_files(dir.path / "cluster_out"));
  const auto summary = nlohmann::json::parse(test::read_file(dir.path / "cluster_out" / "summary.json"));
  EXPECT_EQ(verdicts(summary), verdicts(nlohmann::json::parse(test::read_file(dir.path / "local" / "summary.json"))));
  EXPECT_EQ(summary["parts_failed"], 1);
  const std::string job = summary["slurm_job_id"];
  EXPECT_FALSE(job.empty());
  const auto& broken = summary["parts"][2];
  EXPECT_EQ(broken["part"], "broken");
  EXPECT_EQ(broken["ok"], false);
  EXPECT_EQ(broken["slurm_task_id"], 2);
  EXPECT_EQ(broken["slurm_job_id"], job);
  EXPECT_EQ(broken["errors"][0], "node 'read' (io.read_cloud) failed on part 'broken': broken.ply: line 4: header ends without 'end_header'");
  for (const auto& p : summary["parts"])
    if (p["ok"] == true) {
      EXPECT_GT(p["cache_misses"].get<int>(), 0) << p["part"];
    }

  // submitted again, without waiting, and collected: every cached node from the shared cache
  ASSERT_EQ(test::run_command(cd + slurm.env() + " " + kScallop + " batch " + kZigzag + parts +
                                  " --executor slurm --cache cache -q --no-wait -o cluster_out", &out), 0) << out;
  EXPECT_NE(out.find("collect the results with: scallop batch --collect cluster_out"), std::string::npos) << out;
  ASSERT_EQ(test::run_command(cd + slurm.env() + " " + kScallop + " batch --collect cluster_out", &out), 2) << out;
  const auto again = nlohmann::json::parse(test::read_file(dir.path / "cluster_out" / "summary.json"));
  EXPECT_NE(again["slurm_job_id"], job);
  EXPECT_EQ(verdicts(again), verdicts(summary));
  for (const auto& p : again["parts"])
    if (p["ok"] == true) {
      EXPECT_EQ(p["cache_misses"], 0) << p["part"];
      EXPECT_GT(p["cache_hits"].get<int>(), 0) << p["part"];
    }
  EXPECT_TRUE(local == output_files(dir.path / "cluster_out"));
  std::printf("first submission through Slurm: %.1f s\n", seconds);
}

TEST(Slurm, DryRunWritesAndPrintsTheJobScriptAndSubmitsNothing) {
  test::TempDir dir;
  write_wavy_patch(dir.path / "a part.ply", 4, 0);
  test::write_file(dir.path / "b.ply", "");
  std::string out;
  ASSERT_EQ(test::run_command("cd " + dir.str() + " && SLURM_CONF=/nonexistent " + kScallop + " batch " + kZigzag +
                                  " 'a part.ply' b.ply --executor slurm --partition short --time 20 --cpus-per-part 2"
                                  " --array-limit 8 --cache /shared/cache --set tool_radius=3 -o out --dry-run",
                              &out), 0) << out;
  const std::string script = test::read_file(dir.path / "out" / "slurm" / "job.sh");
  EXPECT_NE(out.find(script), std::string::npos) << out;
  for (const std::string& line : std::vector<std::string>{"#SBATCH --array=0-1%8\n", "#SBATCH --cpus-per-task=2\n", "#SBATCH --partition=short\n", "#SBATCH --time=20\n",
        "#SBATCH --chdir=" + fs::canonical(dir.path).string() + "\n",
        "  0) part='a part.ply' name='a part' ;;\n", "  1) part=b.ply name=b ;;\n",
        " run " + kZigzag + " --input cloud=\"$part\" --part \"$name\" \\\n  --set tool_radius=3 --cache /shared/cache --threads 2 \\\n  -o out/\"$name\" --result out/slurm/results/\"$name\".json\n"})
    EXPECT_NE(script.find(line), std::string::npos) << line << "\nin\n" << script;
  EXPECT_NE(out.find("not submitted; the job script is out/slurm/job.sh"), std::string::npos) << out;
  auto batch = nlohmann::json::parse(test::read_file(dir.path / "out" / "slurm" / "batch.json"));
  EXPECT_EQ(batch["job_id"], "");
  EXPECT_EQ(batch["names"], (nlohmann::json{"a part", "b"}));
  // never submitted: --collect reports every part as without a result, from the files alone
  EXPECT_EQ(test::run_command("cd " + dir.str() + " && " + kScallop + " batch --collect out -q", &out), 1) << out;
  EXPECT_NE(out.find("Slurm task 1 left no result; its log out/slurm/logs/1.log is empty or missing"), std::string::npos) << out;
}

TEST(Slurm, OptionsOfOneExecutorAreRefusedWithTheOther) {
  std::string out;
  EXPECT_EQ(test::run_command(kScallop + " batch " + kZigzag + " a.ply --partition short -o out", &out), 2);
  EXPECT_NE(out.find("error: --partition: only with --executor slurm"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(kScallop + " batch " + kZigzag + " a.ply --executor slurm -j 4 -o out", &out), 2);
  EXPECT_NE(out.find("error: -j: not with --executor slurm, where --array-limit bounds the tasks running at once"),
            std::string::npos) << out;
  EXPECT_EQ(test::run_command(kScallop + " batch " + kZigzag + " --collect out", &out), 2);
  EXPECT_NE(out.find("error: --collect DIR takes no graph, parts or -o"), std::string::npos) << out;
  EXPECT_EQ(test::run_command(kScallop + " batch " + kZigzag + " a.ply", &out), 2);
  EXPECT_NE(out.find("error: batch needs a graph, at least one part and -o DIR (or --collect DIR)"), std::string::npos) << out;
}

}  // namespace
}  // namespace scallop
