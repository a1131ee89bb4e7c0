#include "nodes/mesh/external_process.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <fstream>
#include <stdexcept>
#include <thread>

extern char** environ;

namespace scallop {
namespace fs = std::filesystem;

std::optional<fs::path> find_executable(const std::string& name) {
  auto executable = [](const fs::path& p) {
    struct stat st{};
    return ::stat(p.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::access(p.c_str(), X_OK) == 0;
  };
  if (name.empty()) return std::nullopt;
  if (name.find('/') != std::string::npos) return executable(name) ? std::optional<fs::path>(name) : std::nullopt;
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "";
  std::size_t at = 0;
  while (at <= dirs.size()) {
    std::size_t end = dirs.find(':', at);
    if (end == std::string::npos) end = dirs.size();
    const std::string dir = dirs.substr(at, end - at);
    const fs::path candidate = fs::path(dir.empty() ? "." : dir) / name;
    if (executable(candidate)) return candidate;
    at = end + 1;
  }
  return std::nullopt;
}

ProcessResult run_process(const std::vector<std::string>& argv, const fs::path& log, const fs::path& tmpdir,
                          double timeout_s, const std::function<void(double)>& waiting) {
  if (argv.empty()) throw std::runtime_error("no program to run");
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<std::string> env_text;
  for (char** e = environ; *e; ++e)
    if (tmpdir.empty() || std::strncmp(*e, "TMPDIR=", 7) != 0) env_text.emplace_back(*e);
  if (!tmpdir.empty()) env_text.push_back("TMPDIR=" + tmpdir.string());
  std::vector<char*> env;
  for (std::string& e : env_text) env.push_back(e.data());
  env.push_back(nullptr);
  // fork and exec rather than posix_spawn, for one thing posix_spawn cannot ask: the child is
  // killed when this thread ends (the run stopped by Ctrl-C, a Slurm time limit or SIGKILL), so
  // that a Blender run does not outlive the scallop that started it. Between fork and exec the
  // child only makes system calls.
  const pid_t parent = ::getpid();
  int ready[2];  // closed on exec; the child writes its errno into it if exec fails
  if (::pipe2(ready, O_CLOEXEC) != 0) throw std::runtime_error(std::string("cannot run ") + argv[0] + ": " + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(ready[0]), ::close(ready[1]);
    throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(err));
  }
  if (pid == 0) {
    ::close(ready[0]);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);  // the parent ended before prctl
    const int in = ::open("/dev/null", O_RDONLY), out = ::open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0600);
    if (in >= 0 && out >= 0 && ::dup2(in, 0) >= 0 && ::dup2(out, 1) >= 0 && ::dup2(out, 2) >= 0)
      ::execve(argv[0].c_str(), args.data(), env.data());
    const int err = errno;
    (void)!::write(ready[1], &err, sizeof err);
    ::_exit(127);
  }
  ::close(ready[1]);
  int exec_error = 0;
  ssize_t got;
  while ((got = ::read(ready[0], &exec_error, sizeof exec_error)) < 0 && errno == EINTR) {
  }
  ::close(ready[0]);
  if (got == sizeof exec_error) {
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(exec_error));
  }

  ProcessResult r;
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  double next_call = 1;
  int status = 0;
  while (true) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) throw std::runtime_error(std::string("waiting for ") + argv[0] + ": " + std::strerror(errno));
    if (elapsed() > timeout_s) {
      ::kill(pid, SIGKILL);
      while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
      }
      r.timed_out = true;
      break;
    }
    if (waiting && elapsed() >= next_call) {
      waiting(elapsed());
      next_call += 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  r.seconds = elapsed();
  if (WIFEXITED(status)) r.exit_status = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

std::vector<std::string> last_lines(const fs::path& file, std::size_t n) {
  std::ifstream in(file);
  std::deque<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
    // Keep a margin for the empty lines at the end that are dropped below.
    if (lines.size() > n + 64) lines.pop_front();
  }
  while (!lines.empty() && lines.back().find_first_not_of(" \t") == std::string::npos) lines.pop_back();
  while (lines.size() > n) lines.pop_front();
  return {lines.begin(), lines.end()};
}

PrivateTempDir::PrivateTempDir(const std::string& prefix) {
  std::string templ = (fs::temp_directory_path() / (prefix + "XXXXXX")).string();
  if (!::mkdtemp(templ.data())) throw std::runtime_error("cannot make a temporary folder " + templ + ": " + std::strerror(errno));
  path_ = templ;
}

PrivateTempDir::~PrivateTempDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

}  // namespace scallop
