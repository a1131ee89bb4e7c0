#include "nodes/mesh/external_process.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <thread>

#include "tests/test_support.h"

namespace scallop {
namespace {

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(RunProcess, OutputGoesToTheLogAndTheExitStatusIsKept) {
  test::TempDir dir;
  const ProcessResult r =
      run_process({"/bin/sh", "-c", "echo out; echo err >&2; echo \"$TMPDIR\"; exit 3"}, dir.path / "log", dir.path, 60);
  EXPECT_EQ(r.exit_status, 3);
  EXPECT_EQ(r.signal, 0);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(read_text(dir.path / "log"), "out\nerr\n" + dir.path.string() + "\n");
}

TEST(RunProcess, AProgramThatCannotRunIsAnError) {
  test::TempDir dir;
  EXPECT_EQ(test::error_of<std::runtime_error>([&] { run_process({"/nonexistent/blender"}, dir.path / "log", "", 60); }),
            "cannot run /nonexistent/blender: No such file or directory");
}

TEST(RunProcess, ARunLongerThanTheLimitIsKilled) {
  test::TempDir dir;
  const ProcessResult r = run_process({"/bin/sleep", "30"}, dir.path / "log", "", 0.2);
  EXPECT_TRUE(r.timed_out);
  EXPECT_EQ(r.signal, SIGKILL);
  EXPECT_LT(r.seconds, 10);
}

// A scallop run stopped by SIGKILL (Ctrl-C, a Slurm limit) must not leave its Blender running:
// a forked copy of this process starts a child that writes its pid and sleeps, and is killed.
TEST(RunProcess, TheChildEndsWithTheRunThatStartedIt) {
  test::TempDir dir;
  const std::string pid_file = (dir.path / "sleeper.pid").string();
  const pid_t helper = ::fork();
  ASSERT_GE(helper, 0);
  if (helper == 0) {
    run_process({"/bin/sh", "-c", "echo $$ > " + pid_file + ".tmp; mv " + pid_file + ".tmp " + pid_file + "; exec sleep 60"},
                "/dev/null", "", 120);
    ::_exit(0);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (!std::filesystem::exists(pid_file) && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(std::filesystem::exists(pid_file));
  const pid_t sleeper = std::stoi(read_text(pid_file));
  ASSERT_EQ(::kill(sleeper, 0), 0);  // running
  ::kill(helper, SIGKILL);
  int status = 0;
  ::waitpid(helper, &status, 0);
  // Gone, or a zombie waiting for init to reap it.
  auto alive = [&] {
    std::ifstream stat("/proc/" + std::to_string(sleeper) + "/stat");
    std::string pid, name, state;
    return stat >> pid >> name >> state && state != "Z";
  };
  while (alive() && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_FALSE(alive());
  if (alive()) ::kill(sleeper, SIGKILL);
}

}  // namespace
}  // namespace scallop
