// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Timing and memory helpers shared by the stage runners under bench/ (header-only).
#include <sys/resource.h>

#include <chrono>

namespace pointsurf::bench {

using Clock = std::chrono::steady_clock;

// Seconds elapsed since `t`.
inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Peak resident memory of this process so far, MiB.
inline double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

}  // namespace pointsurf::bench
