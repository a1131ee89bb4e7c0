// Progress of a parallel loop, reported through an optional callback.
//
// Chunks of a tbb::parallel_for call done(items) as they finish; the fraction of the n items done,
// mapped onto [from, to], goes to the callback from whichever thread finished a chunk, one thread
// at a time (the others skip that report), so the callback need not be thread-safe. Fractions are
// non-decreasing and the last is `to` once every item is done.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <functional>
#include <mutex>

namespace scallop {

class ParallelProgress {
 public:
  ParallelProgress(const std::function<void(double)>& report, std::size_t n, double from = 0,
                   double to = 1)
      : report_(report), n_(n), from_(from), to_(to) {}

  void done(std::size_t items) {
    if (!report_) return;
    const std::size_t d = done_ += items;
    if (d >= n_) {  // the last chunk always reports, after any report still under way
      std::lock_guard<std::mutex> lock(lock_);
      report_locked(n_);
    } else if (lock_.try_lock()) {
      report_locked(d);
      lock_.unlock();
    }
  }

 private:
  void report_locked(std::size_t d) {
    const double f = from_ + (to_ - from_) * static_cast<double>(std::min(d, n_)) / std::max<std::size_t>(n_, 1);
    if (f <= last_) return;  // a slower thread with an older count
    last_ = f;
    report_(f);
  }

  const std::function<void(double)>& report_;
  std::size_t n_;
  double from_, to_;
  double last_ = -1;
  std::atomic<std::size_t> done_{0};
  std::mutex lock_;
};

}  // namespace scallop
