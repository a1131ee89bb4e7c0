#include "engine/events.h"

#include <unistd.h>

#include <chrono>
#include <stdexcept>

namespace scallop {

double seconds_since_start() {
  static const auto start = std::chrono::steady_clock::now();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

JsonLinesSink::JsonLinesSink(const std::string& path) : out_(path) {
  if (!out_) throw std::runtime_error("cannot write events file '" + path + "'");
}

void JsonLinesSink::on_event(const nlohmann::json& event) {
  std::lock_guard lock(mutex_);
  out_ << event.dump() << "\n";
  out_.flush();
}

TerminalReporter::TerminalReporter(std::FILE* out, bool explain, bool quiet)
    : out_(out), tty_(::isatty(::fileno(out)) != 0), explain_(explain), quiet_(quiet) {}

void TerminalReporter::draw_bar(const std::string& label) {
  constexpr int width = 30;
  int filled = total_ > 0 ? done_ * width / total_ : 0;
  std::string bar(filled, '#');
  bar += std::string(width - filled, '.');
  std::fprintf(out_, "\r\033[K[%s] %d/%d  %s", bar.c_str(), done_, total_, label.c_str());
  std::fflush(out_);
  bar_shown_ = true;
}

std::string warning_line(const nlohmann::json& e) {
  const std::string part = e.value("part", "");
  return "warning: node '" + e.value("node", "") + "' (" + e.value("type", "") + ")" +
         (part.empty() ? "" : " on part '" + part + "'") + ": " + e.value("message", "");
}

void TerminalReporter::on_event(const nlohmann::json& e) {
  const std::string kind = e.value("event", "");
  if (quiet_ && kind != "node_warning") return;
  std::lock_guard lock(mutex_);
  if (kind == "node_warning") {
    if (bar_shown_) std::fprintf(out_, "\r\033[K");
    bar_shown_ = false;
    std::fprintf(out_, "%s\n", warning_line(e).c_str());
    std::fflush(out_);
    return;
  }
  std::string part = e.value("part", "");
  std::string who = (part.empty() ? "" : part + ": ") + e.value("node", "");
  if (kind == "node_start" && tty_) {
    draw_bar(who + " (" + e.value("type", "") + ")");
  } else if (kind == "node_progress" && tty_) {
    char pct[32];
    std::snprintf(pct, sizeof pct, " %3.0f%%", 100.0 * e.value("fraction", 0.0));
    draw_bar(who + pct + (e.value("message", "").empty() ? "" : " " + e.value("message", "")));
  } else if (kind == "node_finish") {
    ++done_;
    if (bar_shown_) std::fprintf(out_, "\r\033[K");
    std::string status = e.value("status", "");
    std::fprintf(out_, "  %-28s %-22s %-8s %9.3f s", who.c_str(), e.value("type", "").c_str(), status.c_str(),
                 e.value("seconds", 0.0));
    if (explain_ && !e.value("cache", "").empty())
      std::fprintf(out_, "  cache %s%s", e.value("cache", "").c_str(),
                   e.value("why", "").empty() ? "" : (": " + e.value("why", "")).c_str());
    if (status == "failed") std::fprintf(out_, "\n    error: %s", e.value("error", "").c_str());
    if (status == "skipped") std::fprintf(out_, "  (%s)", e.value("why", "").c_str());
    std::fprintf(out_, "\n");
    if (tty_ && done_ < total_) draw_bar("");
    else bar_shown_ = false;
  }
  std::fflush(out_);
}

}  // namespace scallop
