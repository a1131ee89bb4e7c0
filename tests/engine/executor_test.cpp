// Executor and cache: hits, partial re-execution, failure isolation, concurrency, crash safety.
#include "engine/executor.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Core>
#include <filesystem>
#include <set>
#include <sstream>
#include <tuple>

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

// Entries are written beside the nodes that follow. One that cannot be written (a full disk)
// leaves the run and its outputs sound: each node says so in a warning, and the next run
// computes again what was not kept.
TEST(Cache, AnEntryThatCannotBeWrittenIsAWarningNotAFailure) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  {
    DiskCache full(dir.str());
    full.after_partial_write = [](const std::string&) { throw std::runtime_error("No space left on device"); };
    const RunResult r = run(reg, kChain, &full);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(total(r), 10.0);
    for (const NodeRun& node : r.nodes) {
      ASSERT_EQ(node.warnings.size(), 1u) << node.id;
      EXPECT_EQ(node.warnings[0], "its result could not be kept in the cache: No space left on device");
    }
  }
  DiskCache cache(dir.str());
  EXPECT_EQ(run(reg, kChain, &cache).executed(), 4);
  EXPECT_EQ(run(reg, kChain, &cache).executed(), 0);  // kept this time
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
  // the half-written temp file is left aside, beside the entry, named after host and process
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  std::vector<std::string> left;
  for (const auto& f : fs::directory_iterator(fs::path(cache.entry_path(key)).parent_path()))
    left.push_back(f.path().filename().string());
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].rfind(key + ".entry." + host + "." + std::to_string(pid) + ".", 0), 0u) << left[0];
  EXPECT_EQ(fs::path(left[0]).extension(), ".tmp");
  auto lookup = cache.load(key, reg.values());
  EXPECT_FALSE(lookup.hit);
  EXPECT_EQ(lookup.why, "no entry");
}

TEST(Cache, ManyWritersOfOneKeyNeverShowAReaderAPartialEntry) {
  // Tasks of a batch on a cluster write the same key into one shared folder: four processes
  // store one large entry over and over while this one reads it back.
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  const std::string key = "0123456789abcdef0123456789abcdef";
  std::map<std::string, ValuePtr> outputs;
  for (int i = 0; i < 2000; ++i) outputs["out" + std::to_string(i)] = std::make_shared<Number>(i);
  std::vector<pid_t> writers;
  for (int w = 0; w < 4; ++w) {
    pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      DiskCache cache(dir.str());
      for (int n = 0; n < 50; ++n) cache.store(key, outputs);
      ::_exit(0);
    }
    writers.push_back(pid);
  }
  DiskCache cache(dir.str());
  int hits = 0, reads = 0;
  for (bool running = true; running; ++reads) {
    auto lookup = cache.load(key, reg.values());
    if (lookup.hit) {
      ++hits;
      ASSERT_EQ(lookup.outputs.size(), outputs.size());
      EXPECT_EQ(std::dynamic_pointer_cast<const Number>(lookup.outputs.at("out1999"))->value, 1999.0);
    } else {
      ASSERT_EQ(lookup.why, "no entry");  // before the first rename; never "damaged entry (...)"
    }
    running = false;
    for (pid_t pid : writers) running |= ::waitpid(pid, nullptr, WNOHANG) == 0;
  }
  for (pid_t pid : writers) ::waitpid(pid, nullptr, 0);
  EXPECT_GT(hits, 0) << reads << " reads";
  // every writer's temp file was renamed into place: the entry alone is left
  EXPECT_EQ(std::distance(fs::directory_iterator(fs::path(cache.entry_path(key)).parent_path()), fs::directory_iterator()), 1);
  EXPECT_TRUE(cache.load(key, reg.values()).hit);
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
  EXPECT_EQ(lookup.why, "damaged entry (checksum mismatch)");
  EXPECT_FALSE(fs::exists(path));  // dropped, so the recomputed entry takes its place
  executions().clear();
  RunResult again = run(reg, kChain, &cache);
  EXPECT_EQ(again.executed(), 1);
  EXPECT_EQ(total(again), 10.0);

  // a flipped byte in the middle of the chain, whose consumer is cached: recomputed from its
  // inputs (loaded from the cache), and the cache holds it again
  std::string sum = cache.entry_path(first.find("sum")->key);
  std::string bytes = test::read_file(sum);
  bytes[bytes.size() / 2] ^= 0x20;
  test::write_file(sum, bytes);
  executions().clear();
  RunResult healed = run(reg, kChain, &cache);
  ASSERT_TRUE(healed.ok()) << healed.errors[0];
  EXPECT_EQ(healed.executed(), 1);
  EXPECT_EQ(executions()["sum"], 1);
  EXPECT_EQ(healed.find("sum")->why, "damaged entry (checksum mismatch); recomputed so that the cache holds it again");
  EXPECT_EQ(run(reg, kChain, &cache).executed(), 0);
}

// kChain, run once with a cache; then `damage` is done to the entries; the next run's result.
template <class Damage>
RunResult rerun_after(const Registry& reg, Damage damage) {
  test::TempDir dir;
  DiskCache cache(dir.str());
  RunResult first = run(reg, kChain, &cache);
  EXPECT_TRUE(first.ok());
  damage(cache, [&](const char* id) { return cache.entry_path(first.find(id)->key); });
  executions().clear();
  RunResult again = run(reg, kChain, &cache);
  EXPECT_EQ(run(reg, kChain, &cache).executed(), 0) << "the cache is whole again";
  return again;
}

TEST(Cache, DeletedMiddleEntryIsRecomputedFromItsInputsWhenItsConsumerIsCached) {
  // was: 'sum' ran without its inputs ("input 'a' is not connected") on every later run
  Registry reg = test::make_test_registry();
  RunResult r = rerun_after(reg, [](DiskCache&, auto entry) { fs::remove(entry("sum")); });
  ASSERT_TRUE(r.ok()) << r.errors[0];
  EXPECT_EQ(total(r), 10.0);
  EXPECT_EQ(r.executed(), 1);
  EXPECT_EQ(executions()["sum"], 1);
  EXPECT_EQ(r.find("sum")->status, "ok");
  EXPECT_EQ(r.find("sum")->why, "entry missing; recomputed so that the cache holds it again");
  for (const char* id : {"a", "b"}) {  // its inputs: loaded from the cache, not recomputed
    EXPECT_EQ(r.find(id)->status, "cached") << id;
    EXPECT_EQ(r.find(id)->why, "same type, version, parameters and inputs") << id;
  }
  EXPECT_EQ(r.find("twice")->status, "cached");
}

TEST(Cache, DeletedEntriesRecomputeExactlyTheMissingAncestry) {
  // 'sum' and its input 'a' are gone: both run, 'b' is loaded, 'twice' stays cached
  Registry reg = test::make_test_registry();
  RunResult r = rerun_after(reg, [](DiskCache&, auto entry) {
    fs::remove(entry("sum"));
    fs::remove(entry("a"));
  });
  ASSERT_TRUE(r.ok()) << r.errors[0];
  EXPECT_EQ(total(r), 10.0);
  std::map<std::string, std::string> status;
  for (const auto& n : r.nodes) status[n.id] = n.status;
  EXPECT_EQ(status, (std::map<std::string, std::string>{{"a", "ok"}, {"b", "cached"}, {"sum", "ok"}, {"twice", "cached"}}));
  EXPECT_EQ(executions(), (std::map<std::string, int>{{"a", 1}, {"sum", 1}}));
}

TEST(Cache, EntryCopiedOverAnotherKeysFileIsAMissNotTheOtherValue) {
  // 'sum' (5) copied over 'twice' (10): it passes its checksum, but holds another key
  Registry reg = test::make_test_registry();
  RunResult r = rerun_after(reg, [](DiskCache&, auto entry) {
    fs::copy_file(entry("sum"), entry("twice"), fs::copy_options::overwrite_existing);
  });
  ASSERT_TRUE(r.ok()) << r.errors[0];
  EXPECT_EQ(total(r), 10.0);
  EXPECT_EQ(r.find("twice")->status, "ok");
  EXPECT_EQ(r.find("twice")->cache, "miss");
  EXPECT_EQ(r.find("twice")->why, "entry holds another key");
  EXPECT_EQ(r.find("sum")->status, "cached");
  EXPECT_EQ(r.executed(), 1);
}

TEST(Cache, EntryOfAnOlderFormatIsACleanMiss) {
  // format 2 had no key in the entry: such an entry is recomputed, never an error
  Registry reg = test::make_test_registry();
  RunResult r = rerun_after(reg, [](DiskCache&, auto entry) {
    test::write_file(entry("twice"), std::string("SCALLOP-CACHE 2\n") + std::string(8, '\0') +
                                         "0123456789abcdef0123456789abcdef");
  });
  ASSERT_TRUE(r.ok()) << r.errors[0];
  EXPECT_EQ(total(r), 10.0);
  EXPECT_EQ(r.find("twice")->why, "entry of another cache format (2, now 3)");
  EXPECT_EQ(r.executed(), 1);
}

TEST(Cache, NodeNotCachedOnDiskWhoseConsumersAreCachedDoesNotRun) {
  Registry reg = test::make_test_registry();
  const char* text = R"({"scallop_graph": 1, "nodes": [
      {"id": "a", "type": "test.const", "params": {"value": 4}},
      {"id": "pass", "type": "test.barrier", "params": {"parties": 1}, "inputs": {"a": "a.out"}},
      {"id": "twice", "type": "test.add", "params": {"times": 2}, "inputs": {"a": "pass.out"}}],
      "outputs": {"total": "twice.out"}})";
  test::TempDir dir;
  DiskCache cache(dir.str());
  ASSERT_TRUE(run(reg, text, &cache).ok());
  executions().clear();
  RunResult r = run(reg, text, &cache);
  ASSERT_TRUE(r.ok()) << r.errors[0];
  EXPECT_EQ(total(r), 8.0);
  EXPECT_EQ(r.executed(), 0);
  EXPECT_EQ(r.find("pass")->status, "skipped");
  EXPECT_EQ(r.find("pass")->cache, "off");
  EXPECT_EQ(r.find("pass")->why, "not run: nothing downstream needs it");
}

TEST(Cache, LoadDecodesOnlyThePortsAsked) {
  Registry reg = test::make_test_registry();
  test::TempDir dir;
  DiskCache cache(dir.str());
  cache.store("k", {{"one", std::make_shared<Number>(1)}, {"two", std::make_shared<Number>(2)}});
  const std::set<std::string> two{"two"};
  DiskCache::Lookup some = cache.load("k", reg.values(), &two), all = cache.load("k", reg.values());
  ASSERT_TRUE(some.hit && all.hit);
  ASSERT_EQ(some.outputs.size(), 1u);
  EXPECT_EQ(std::dynamic_pointer_cast<const Number>(some.outputs.at("two"))->value, 2.0);
  ASSERT_EQ(all.outputs.size(), 2u);
  EXPECT_EQ(std::dynamic_pointer_cast<const Number>(all.outputs.at("one"))->value, 1.0);
}

TEST(Cache, VectorsReadBackWholeAcrossTheReadersChunks) {
  // bin::read_vector reads 64 KiB at a time: lengths below, at and across a chunk's end
  for (std::size_t n : {0, 1, 8191, 8192, 8193, 20001}) {
    std::vector<double> v(n);
    std::vector<Eigen::Vector3d> w(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = 0.5 * double(i), w[i] = {double(i), -double(i), 1.0 / (i + 1)};
    std::stringstream io;
    bin::write_vector(io, v);
    bin::write_vector(io, w);
    EXPECT_EQ(bin::read_vector<double>(io), v) << n;
    EXPECT_EQ(bin::read_vector<Eigen::Vector3d>(io), w) << n;
  }
  std::stringstream cut;
  bin::write_vector(cut, std::vector<double>(10000, 1.0));
  std::string bytes = cut.str();
  std::stringstream truncated(bytes.substr(0, bytes.size() - 8));
  EXPECT_THROW(bin::read_vector<double>(truncated), std::runtime_error);
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

// test.measure (Number -> Length) and test.half (Length -> Number) beside the test nodes, with
// Length's serialisation at `length_format`.
Registry length_registry(int length_format) {
  Registry reg = test::make_test_registry();
  reg.values().add({"Length", "txt", "a number again", Number::deserialize, length_format});
  for (auto [type, in, out] : {std::tuple{"test.measure", "Number", "Length"}, std::tuple{"test.half", "Length", "Number"}}) {
    NodeDecl d;
    d.type = type;
    d.input("a", in, "").output("out", out, "");
    d.run = [](NodeContext& ctx) { ctx.set("out", Number(ctx.input<Number>("a")->value / 2)); };
    reg.add(d);
  }
  return reg;
}

// a ─ measure ─ half     b ─ sum
const char* kLengths = R"({
  "scallop_graph": 1, "name": "lengths",
  "nodes": [
    {"id": "a", "type": "test.const", "params": {"value": 4}},
    {"id": "measure", "type": "test.measure", "inputs": {"a": "a.out"}},
    {"id": "half", "type": "test.half", "inputs": {"a": "measure.out"}},
    {"id": "b", "type": "test.const", "params": {"value": 3}},
    {"id": "sum", "type": "test.add", "inputs": {"a": "b.out"}}
  ],
  "outputs": {"half": "half.out", "sum": "sum.out"}
})";

TEST(Executor, AValueTypesFormatIsInTheKeysOfTheNodesThatUseItOnly) {
  const Registry before = length_registry(1), after = length_registry(2);
  test::TempDir dir;
  DiskCache cache(dir.str());
  const RunResult first = run(before, kLengths, &cache), second = run(after, kLengths, &cache);
  ASSERT_TRUE(first.ok() && second.ok());
  for (const char* id : {"measure", "half"}) {  // they write and read Length
    EXPECT_NE(first.find(id)->key, second.find(id)->key) << id;
    EXPECT_EQ(second.find(id)->status, "ok") << id;
    EXPECT_EQ(second.find(id)->why, "the cache format of value type Length changed (1 -> 2)") << id;
  }
  for (const char* id : {"a", "b", "sum"}) {  // Number only
    EXPECT_EQ(first.find(id)->key, second.find(id)->key) << id;
    EXPECT_EQ(second.find(id)->status, "cached") << id;
  }
}

}  // namespace
}  // namespace scallop
