// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <functional>
#include <string>
#include <string_view>
#include <utility>

namespace pointsurf {

/// Progress of a long stage: called with the finished fraction in [0, 1]; return false to
/// cancel (the stage then throws CancelledError). May be called from any worker thread, but
/// never from two threads at once. An empty function means no reporting.
using ProgressCallback = std::function<bool(double fraction)>;

/// A ProgressCallback that also hears which phase the stage is in ("octree", "solve level 7").
/// Store one in a ProgressCallback; report_phase() finds it there, and sub_progress() passes
/// the names through. A plain callback (a lambda, a Python function) simply hears no phases.
struct PhasedProgress {
  ProgressCallback on_fraction;                          // as a ProgressCallback; empty: keep going
  std::function<void(std::string_view name)> on_phase;  // called from the stage's serial code
  bool operator()(double fraction) const { return on_fraction ? on_fraction(fraction) : true; }
};

/// Tells `progress` that the stage entered phase `name`; nothing when it holds no PhasedProgress.
inline void report_phase(const ProgressCallback& progress, std::string_view name) {
  if (const PhasedProgress* p = progress.target<PhasedProgress>(); p != nullptr && p->on_phase) p->on_phase(name);
}

/// The callback for the part [begin, end] of `whole` (empty when `whole` is): its fraction f is
/// reported as begin + (end - begin) f; phases pass through, and `phase`, when given, is
/// reported at once.
inline ProgressCallback sub_progress(const ProgressCallback& whole, double begin, double end, std::string_view phase = {}) {
  if (!whole) return {};
  if (!phase.empty()) report_phase(whole, phase);
  PhasedProgress part;
  part.on_fraction = [whole, begin, end](double f) { return whole(begin + (end - begin) * f); };
  if (whole.target<PhasedProgress>() != nullptr) part.on_phase = [whole](std::string_view name) { report_phase(whole, name); };
  return part;
}

}  // namespace pointsurf
