// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <algorithm>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>

namespace pointsurf {

/// Progress of a long stage: called with the finished fraction in [0, 1]; return false to
/// cancel (the stage then throws CancelledError). May be called from any worker thread, but
/// never from two threads at once. An empty function means no reporting.
using ProgressCallback = std::function<bool(double fraction)>;

/// What a stage expects of its whole run once it knows (Poisson after its octree): the seconds
/// it should take on the 2-core machine its cost model was fitted on, and the size of its output
/// (triangles, points). A caller that runs more work after the stage weighs its own part against
/// the stage's by these (bench/notes/progress.md).
struct ProgressForecast {
  double seconds = 0.0;
  double output_size = 0.0;
};

/// A ProgressCallback that also hears which phase the stage is in ("octree", "solve level 7")
/// and the stage's forecast. Store one in a ProgressCallback; report_phase() and
/// report_forecast() find it there, and sub_progress() passes the phase names through (not the
/// forecasts: they describe the callee's whole run, which only its own caller can weigh). A
/// plain callback (a lambda, a Python function) simply hears neither.
struct PhasedProgress {
  ProgressCallback on_fraction;                          // as a ProgressCallback; empty: keep going
  std::function<void(std::string_view name)> on_phase;  // called from the stage's serial code
  std::function<void(const ProgressForecast&)> on_forecast;  // likewise
  bool operator()(double fraction) const { return on_fraction ? on_fraction(fraction) : true; }
};

/// Tells `progress` that the stage entered phase `name`; nothing when it holds no PhasedProgress.
inline void report_phase(const ProgressCallback& progress, std::string_view name) {
  if (const PhasedProgress* p = progress.target<PhasedProgress>(); p != nullptr && p->on_phase) p->on_phase(name);
}

/// Tells `progress` what the stage expects of its whole run; nothing when it holds no
/// PhasedProgress with an on_forecast.
inline void report_forecast(const ProgressCallback& progress, const ProgressForecast& forecast) {
  if (const PhasedProgress* p = progress.target<PhasedProgress>(); p != nullptr && p->on_forecast) p->on_forecast(forecast);
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

/// A part [begin, end] of `whole` whose end may move while the part runs, once the work ahead
/// is known (a cost model decided after an octree): callback() maps the part's fraction f onto
/// [begin, end]; move_end(e) keeps what was reported and stretches the rest of the part, from
/// the last fraction heard, to end at e, so the reports stay continuous and never go back.
/// Copies share the part. An empty `whole` gives an empty callback.
class MovableProgress {
 public:
  MovableProgress(ProgressCallback whole, double begin, double end) : state_(std::make_shared<State>()) {
    state_->whole = std::move(whole);
    state_->reported = begin;
    state_->end = std::max(begin, end);
  }

  /// The part's callback; `on_forecast`, when given, hears the forecasts reported to it.
  ProgressCallback callback(std::function<void(const ProgressForecast&)> on_forecast = {}) const {
    if (!state_->whole) return {};
    PhasedProgress part;
    part.on_fraction = [state = state_](double f) {
      double to;
      {
        const std::lock_guard lock(state->mutex);
        state->heard = std::max(state->heard, std::clamp(f, 0.0, 1.0));
        to = state->map(state->heard);
      }
      return state->whole(to);
    };
    if (state_->whole.target<PhasedProgress>() != nullptr) part.on_phase = [whole = state_->whole](std::string_view name) { report_phase(whole, name); };
    part.on_forecast = std::move(on_forecast);
    return part;
  }

  /// Moves the part's end to `end` (at least what was reported already).
  void move_end(double end) {
    const std::lock_guard lock(state_->mutex);
    state_->reported = state_->map(state_->heard);
    state_->from = state_->heard;
    state_->end = std::max(end, state_->reported);
  }

  double end() const {
    const std::lock_guard lock(state_->mutex);
    return state_->end;
  }

 private:
  struct State {
    ProgressCallback whole;
    mutable std::mutex mutex;
    double from = 0.0, reported = 0.0, end = 1.0;  // the part's fraction `from` was reported as `reported`
    double heard = 0.0;                            // the largest fraction heard
    double map(double f) const { return from >= 1.0 ? end : reported + (end - reported) * (f - from) / (1.0 - from); }
  };
  std::shared_ptr<State> state_;
};

}  // namespace pointsurf
