// Progress and timing events: per-node start/progress/finish, as JSON objects.
//
// Every event has "event", "t" (seconds since the process started), "part" and, for node events,
// "node" and "type". node_finish adds "status" (ok|cached|failed|skipped), "seconds", "cache"
// (hit|miss|off), "why" and "error". node_warning (what a node said with ctx.warn, also replayed
// from the cache with "cached": true) adds "message".
#pragma once

#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace scallop {

double seconds_since_start();

// The terminal's line for a node_warning event: "warning: node 'ID' (TYPE) on part 'P': message"
// (without " on part 'P'" when the part has no name).
std::string warning_line(const nlohmann::json& event);

class EventSink {
 public:
  virtual ~EventSink() = default;
  virtual void on_event(const nlohmann::json& event) = 0;
};

// JSON lines to a file (--events FILE), one event per line, flushed as written.
class JsonLinesSink final : public EventSink {
 public:
  explicit JsonLinesSink(const std::string& path);
  void on_event(const nlohmann::json& event) override;

 private:
  std::mutex mutex_;
  std::ofstream out_;
};

// Human output on stderr: a progress bar redrawn in place on a terminal, plain lines otherwise;
// --explain adds why each node hit or missed the cache. Node warnings are printed even when
// quiet, one line each: "warning: node 'ID' (TYPE) on part 'P': message".
class TerminalReporter final : public EventSink {
 public:
  TerminalReporter(std::FILE* out, bool explain, bool quiet);
  void on_event(const nlohmann::json& event) override;
  void set_total(int nodes) { total_ = nodes; }

 private:
  void draw_bar(const std::string& label);
  std::mutex mutex_;
  std::FILE* out_;
  bool tty_, explain_, quiet_;
  int total_ = 0, done_ = 0;
  bool bar_shown_ = false;
};

// Fans events out to several sinks.
class EventFanout final : public EventSink {
 public:
  void add(EventSink* sink) {
    if (sink) sinks_.push_back(sink);
  }
  void on_event(const nlohmann::json& event) override {
    for (auto* s : sinks_) s->on_event(event);
  }

 private:
  std::vector<EventSink*> sinks_;
};

}  // namespace scallop
