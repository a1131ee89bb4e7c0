// Running an external program (Blender for mesh.quad_remesh) as a child process: no shell, its
// output into a file, a time limit, and a private temporary folder for the files it exchanges.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace scallop {

// The executable a name stands for: a name with a '/' is taken as a path, checked to be an
// executable regular file; a bare name is looked up in the folders of $PATH. nullopt if none.
std::optional<std::filesystem::path> find_executable(const std::string& name);

struct ProcessResult {
  bool timed_out = false;  // killed after the time limit
  int exit_status = -1;    // its exit status when it exited, else -1
  int signal = 0;          // the signal that ended it, if one did
  double seconds = 0;      // wall time
};

// Runs argv[0] (a path, not looked up) with arguments argv[1..], stdin from /dev/null, stdout and
// stderr both appended to log, in this process's environment with TMPDIR set to tmpdir when it is
// not empty (so that what it leaves there when killed goes with that folder). waiting(seconds so
// far) is called about every second while it runs. A run longer than timeout_s is killed
// (SIGKILL, that child alone); so is one whose caller's thread ends first (the run was stopped).
// Throws std::runtime_error when the process cannot be started.
ProcessResult run_process(const std::vector<std::string>& argv, const std::filesystem::path& log,
                          const std::filesystem::path& tmpdir, double timeout_s,
                          const std::function<void(double)>& waiting = {});

// The last n lines of a text file (fewer when it has fewer), without their line ends; empty
// lines at its end skipped.
std::vector<std::string> last_lines(const std::filesystem::path& file, std::size_t n);

// A fresh folder only this user can read (mkdtemp under the system temp folder, its name
// starting with prefix), removed with everything in it when the object dies.
class PrivateTempDir {
 public:
  explicit PrivateTempDir(const std::string& prefix);
  ~PrivateTempDir();
  PrivateTempDir(const PrivateTempDir&) = delete;
  PrivateTempDir& operator=(const PrivateTempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace scallop
