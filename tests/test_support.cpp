#include "tests/test_support.h"

#include <sys/wait.h>

#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>

namespace scallop::test {
namespace fs = std::filesystem;

TempDir::TempDir() {
  std::random_device rd;
  path = fs::temp_directory_path() / ("scallop-test-" + std::to_string(rd()) + std::to_string(rd()));
  fs::create_directories(path);
}
TempDir::~TempDir() {
  std::error_code ec;
  fs::remove_all(path, ec);
}

void Number::serialize(std::ostream& out) const { bin::write_f64(out, value); }
ValuePtr Number::deserialize(std::istream& in) { return std::make_shared<Number>(bin::read_f64(in)); }

std::map<std::string, int>& executions() {
  static std::map<std::string, int> counts;
  return counts;
}

namespace {
std::mutex count_mutex;
void count(const std::string& id) {
  std::lock_guard lock(count_mutex);
  ++executions()[id];
}

// A barrier that fails instead of hanging: proves two nodes run at the same time.
struct Barrier {
  std::mutex m;
  std::condition_variable cv;
  int arrived = 0;
};
Barrier barrier;
}  // namespace

Registry make_test_registry() {
  barrier.arrived = 0;
  Registry r;
  r.values().add({"Number", "txt", "a number", Number::deserialize});
  {
    NodeDecl d;
    d.type = "test.const";
    d.description = "outputs its parameter";
    d.output("out", "Number", "the value").param_float("value", 1.0, -1e9, 1e9, "mm", "the value");
    d.run = [](NodeContext& ctx) {
      count(ctx.node_id());
      ctx.set("out", Number(ctx.number("value")));
    };
    r.add(d);
  }
  {
    NodeDecl d;
    d.type = "test.add";
    d.description = "a + b";
    d.input("a", "Number", "first").input("b", "Number", "second", false).output("out", "Number", "sum");
    d.param_int("times", 1, 1, 10, "", "multiplier");
    d.run = [](NodeContext& ctx) {
      count(ctx.node_id());
      double b = ctx.has_input("b") ? ctx.input<Number>("b")->value : 0.0;
      ctx.set("out", Number((ctx.input<Number>("a")->value + b) * static_cast<double>(ctx.integer("times"))));
    };
    r.add(d);
  }
  {
    NodeDecl d;
    d.type = "test.fail";
    d.description = "always fails";
    d.input("a", "Number", "ignored").output("out", "Number", "never set");
    d.run = [](NodeContext& ctx) {
      count(ctx.node_id());
      throw NodeError("the cloud is empty");
    };
    r.add(d);
  }
  {
    NodeDecl d;
    d.type = "test.barrier";
    d.description = "waits until `parties` barrier nodes run at once";
    d.input("a", "Number", "passed through").output("out", "Number", "a");
    d.param_int("parties", 2, 1, 16, "", "how many must meet");
    d.cache_on_disk = false;
    d.run = [](NodeContext& ctx) {
      count(ctx.node_id());
      std::unique_lock lock(barrier.m);
      ++barrier.arrived;
      barrier.cv.notify_all();
      bool met = barrier.cv.wait_for(lock, std::chrono::seconds(20),
                                     [&] { return barrier.arrived >= ctx.integer("parties"); });
      if (!met) throw NodeError("barrier not met: nodes did not run concurrently");
      ctx.set_output("out", ctx.raw_input("a"));
    };
    r.add(d);
  }
  return r;
}

std::map<std::string, ValuePtr> run_node(const NodeDecl& decl, const nlohmann::json& params,
                                         std::map<std::string, ValuePtr> inputs, std::string* last_progress,
                                         std::vector<std::string>* warnings) {
  nlohmann::json p = nlohmann::json::object();
  for (const auto& pd : decl.params) p[pd.name] = pd.default_value;
  for (const auto& [key, value] : params.items()) p[key] = value;
  NodeContext ctx(decl, "n", "part", p, std::move(inputs), [&](double, const std::string& m) {
    if (last_progress) *last_progress = m;
  }, [&](const std::string& m) {
    if (warnings) warnings->push_back(m);
  });
  decl.run(ctx);
  return ctx.take_outputs();
}

void write_file(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

int run_command(const std::string& command, std::string* output) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  std::string text;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, p)) text.append(buf, n);
  int status = ::pclose(p);
  if (output) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace scallop::test
