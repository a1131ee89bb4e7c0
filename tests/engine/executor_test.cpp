// Executor and cache: hits, partial re-execution, failure isolation, concurrency, crash safety.
#include "engine/executor.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>

#include "engine/file_ref.h"
#include "tests/test_support.h"

namespace scallop {
namespace {
namespace fs = std::filesystem;
using test::executions;
using test::Number;

// a ─┐
//    ├─ sum ─ twice
// b ─┘
const char* kChain = R"({
  "scallop_graph": 1, "name": "chain",
  "params": {"v": 2},
  "nodes": [
    {"id": "a", "type": "test.const", "params": {"value": "$v"}},
    {"id": "b", "type": "test.const", "params": {"value": 3}},
    {"id": "sum", "type": "test.add", "inputs": {"a": "a.out", "b": "b.out"}},
    {"id": "twice", "type": "test.add", "params": {"times": 2}, "inputs": {"a": "sum.out"}}
  ],
  "outputs": {"total": "twice.out"}
})";

double total(const RunResult& r) { return std::dynamic_pointer_cast<const Number>(r.outputs.at("total"))->value; }

RunResult run(const Registry& reg, const char* text, DiskCache* cache, std::vector<std::string> sets = {}) {
  CompileOptions opt;
  opt.sets = std::move(sets);
  RunOptions ro;
  ro.cache = cache;
  ro.part = "p";
  return execute(compile(parse_graph(text), reg, opt), reg, {}, ro);
}

TEST(Executor, RunsInDependencyOrder) {
  Registry reg = test::make_test_registry();
  executions().clear();
  RunResult r = run(reg, kChain, nullptr);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(total(r), 10.0);
  EXPECT_EQ(r.executed(), 4);
}

TEST(Executor, RerunHitsTheCache) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  DiskCache cache(dir.str());
  executions().clear();
  RunResult first = run(reg, kChain, &cache);
  RunResult second = run(reg, kChain, &cache);
  EXPECT_EQ(first.executed(), 4);
  EXPECT_EQ(second.executed(), 0);
  EXPECT_EQ(total(second), 10.0);
  for (const auto& n : second.nodes) {
    EXPECT_EQ(n.status, "cached") << n.id;
    EXPECT_EQ(n.cache, "hit");
  }
  EXPECT_EQ(executions()["sum"], 1);
  // Only what is needed is loaded: the graph output, not the nodes upstream of it.
  EXPECT_EQ(second.find("a")->why, "same type, version, parameters and inputs (not loaded: nothing downstream needs it)");
  EXPECT_EQ(second.find("twice")->why, "same type, version, parameters and inputs");
}

TEST(Executor, ParameterChangeReexecutesOnlyThatNodeAndDependents) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  DiskCache cache(dir.str());
  run(reg, kChain, &cache);
  executions().clear();
  RunResult r = run(reg, kChain, &cache, {"v=5"});
  EXPECT_EQ(total(r), 16.0);
  EXPECT_EQ(r.executed(), 3);
  EXPECT_EQ(executions()["a"], 1);
  EXPECT_EQ(executions()["b"], 0);
  EXPECT_EQ(executions()["sum"], 1);
  EXPECT_EQ(executions()["twice"], 1);
  EXPECT_EQ(r.find("a")->why, "parameter value changed (2.0 -> 5.0)");
  EXPECT_EQ(r.find("sum")->why, "input a changed");
  EXPECT_EQ(r.find("b")->cache, "hit");

  executions().clear();
  RunResult only_last = run(reg, kChain, &cache, {"v=5", "twice.times=3"});
  EXPECT_EQ(only_last.executed(), 1);
  EXPECT_EQ(executions()["twice"], 1);
  EXPECT_EQ(total(only_last), 24.0);
}

TEST(Executor, FailureSkipsDependentsAndIndependentBranchesFinish) {
  Registry reg = test::make_test_registry();
  const char* text = R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const"},
      {"id": "bad", "type": "test.fail", "inputs": {"a": "a.out"}},
      {"id": "after", "type": "test.add", "inputs": {"a": "bad.out"}},
      {"id": "other", "type": "test.add", "inputs": {"a": "a.out"}}],
      "outputs": {"x": "after.out", "y": "other.out"}})";
  RunResult r = run(reg, text, nullptr);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.errors, std::vector<std::string>{"node 'bad' (test.fail) failed on part 'p': the cloud is empty"});
  EXPECT_EQ(r.find("bad")->status, "failed");
  EXPECT_EQ(r.find("after")->status, "skipped");
  EXPECT_EQ(r.find("after")->why, "input from 'bad' is missing");
  EXPECT_EQ(r.find("other")->status, "ok");
  EXPECT_EQ(r.outputs.count("y"), 1u);
  EXPECT_EQ(r.outputs.count("x"), 0u);
}

TEST(Executor, IndependentBranchesOverlapInTime) {
  // Each barrier node waits until both are running: the run only succeeds if they overlap.
  Registry reg = test::make_test_registry();
  const char* text = R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const"},
      {"id": "left", "type": "test.barrier", "inputs": {"a": "a.out"}},
      {"id": "right", "type": "test.barrier", "inputs": {"a": "a.out"}}]})";
  RunResult r = run(reg, text, nullptr);
  ASSERT_TRUE(r.ok()) << r.errors[0];
  const NodeRun* left = r.find("left");
  const NodeRun* right = r.find("right");
  EXPECT_LT(left->start, right->finish);
  EXPECT_LT(right->start, left->finish);
}

TEST(Cache, SecondCacheObjectOnTheSameFolderReusesEntries) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  {
    DiskCache cache(dir.str());
    run(reg, kChain, &cache);
  }
  DiskCache again(dir.str());
  EXPECT_EQ(run(reg, kChain, &again).executed(), 0);
}

TEST(Cache, EntryWhoseWriterWasKilledIsNeverReadBack) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  const std::string key = "00112233445566778899aabbccddeeff";
  pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    DiskCache cache(dir.str());
    cache.after_partial_write = [](const std::string&) { ::raise(SIGKILL); };
    cache.store(key, {{"out", std::make_shared<Number>(42.0)}});
    ::_exit(0);  // not reached
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  DiskCache cache(dir.str());
  EXPECT_FALSE(fs::exists(cache.entry_path(key)));
  EXPECT_FALSE(fs::is_empty(dir.path / "tmp"));  // the half-written temp file is left aside
  auto lookup = cache.load(key, reg.values());
  EXPECT_FALSE(lookup.hit);
  EXPECT_EQ(lookup.why, "no entry");
}

TEST(Cache, CorruptOrTruncatedEntryIsRejectedAndRecomputed) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  DiskCache cache(dir.str());
  RunResult first = run(reg, kChain, &cache);
  std::string path = cache.entry_path(first.find("twice")->key);
  ASSERT_TRUE(fs::exists(path));
  fs::resize_file(path, fs::file_size(path) - 7);
  auto lookup = cache.load(first.find("twice")->key, reg.values());
  EXPECT_FALSE(lookup.hit);
  EXPECT_EQ(lookup.why, "unreadable entry (checksum mismatch), recomputed");
  executions().clear();
  RunResult again = run(reg, kChain, &cache);
  EXPECT_EQ(again.executed(), 1);
  EXPECT_EQ(total(again), 10.0);
}

TEST(Cache, KeyDoesNotDependOnInputFileName) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  test::write_file(dir.path / "one.txt", "same bytes");
  test::write_file(dir.path / "two.txt", "same bytes");
  test::write_file(dir.path / "three.txt", "other bytes");
  auto key = [&](const char* name) { return FileRef::open((dir.path / name).string()).content_key(); };
  EXPECT_EQ(key("one.txt"), key("two.txt"));
  EXPECT_NE(key("one.txt"), key("three.txt"));
}

}  // namespace
}  // namespace scallop
