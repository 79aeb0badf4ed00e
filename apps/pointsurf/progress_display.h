// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What the CLI's progress line says, apart from drawing it: the stage, the fraction, the clock,
// the estimate of the time left and the phase, and when the line is due again. The clock is
// passed in (seconds since the stage began), so the cadence is tested without waiting.
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

namespace pointsurf::cli {

class ProgressDisplay {
public:
  /// The line is first drawn after `first_draw_s` (short stages draw nothing); later it is
  /// redrawn when news arrived and `min_interval_s` passed, and at least every `max_interval_s`.
  static constexpr double first_draw_s = 1.0, min_interval_s = 0.1, max_interval_s = 1.0;

  explicit ProgressDisplay(std::string label) : label_(std::move(label)) {}

  /// Records a reported fraction (clamped to [0, 1], never backwards). Thread-safe.
  void set_fraction(double fraction, double now_s);
  /// Records the phase the stage entered. Thread-safe.
  void set_phase(std::string_view name);

  /// The line to draw at `now_s` (no "\r"), or nothing when no redraw is due. Thread-safe.
  std::optional<std::string> due(double now_s);
  /// The line at `now_s`, due or not.
  std::string line(double now_s) const;

  /// "~12 s left", "~3 min 05 s left"; "estimating" until the fraction is 2 % and 2 s old.
  static std::string time_left_text(double fraction, double elapsed_s);

private:
  std::string line_locked(double now_s) const;

  mutable std::mutex mutex_;
  std::string label_, phase_;
  double fraction_ = 0.0;
  bool news_ = false, drawn_ = false;
  double last_draw_s_ = 0.0;
};

}  // namespace pointsurf::cli
