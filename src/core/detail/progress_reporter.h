// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Progress reporting from parallel loops under the ProgressCallback contract: the callback is
// never entered by two threads at once, and its answer cancels the stage.
#include <algorithm>
#include <atomic>
#include <cstddef>
#include <mutex>

#include "pointsurf/core/error.h"
#include "pointsurf/core/progress.h"

namespace pointsurf::detail {

class ProgressReporter {
public:
  /// Maps `total` units of work onto the fractions [begin, end] of the stage.
  ProgressReporter(const ProgressCallback& callback, double begin, double end, std::size_t total)
      : callback_(callback), begin_(begin), end_(end), total_(total) {}

  /// Records `units` finished units; reports unless another thread is reporting right now
  /// (that report is as good). Thread-safe.
  void advance(std::size_t units) {
    done_.fetch_add(units, std::memory_order_relaxed);
    if (!callback_ || cancelled()) return;
    std::unique_lock lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return;
    // Read under the lock, so successive reports never go backwards.
    const double part = total_ == 0 ? 1.0 : double(done_.load(std::memory_order_relaxed)) / double(total_);
    if (!callback_(begin_ + (end_ - begin_) * std::min(part, 1.0))) cancelled_.store(true, std::memory_order_relaxed);
  }

  /// Reports an absolute fraction of the stage from a serial section.
  void report(double fraction) {
    if (!callback_ || cancelled()) return;
    std::lock_guard lock(mutex_);
    if (!callback_(fraction)) cancelled_.store(true, std::memory_order_relaxed);
  }

  /// True once the callback asked to stop; parallel loops check it to skip remaining work.
  bool cancelled() const { return cancelled_.load(std::memory_order_relaxed); }

  /// Throws CancelledError if the callback asked to stop.
  void throw_if_cancelled() const {
    if (cancelled()) throw CancelledError();
  }

private:
  const ProgressCallback& callback_;
  double begin_, end_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::atomic<bool> cancelled_{false};
  std::mutex mutex_;
};

}  // namespace pointsurf::detail
