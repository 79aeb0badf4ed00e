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

// User + system CPU seconds of this process (all threads) so far: under load from other
// processes, wall time stretches but CPU time much less.
inline double cpu_seconds() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

}  // namespace pointsurf::bench
