// SPDX-License-Identifier: GPL-3.0-or-later
#include "progress_display.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace pointsurf::cli {

void ProgressDisplay::set_fraction(double fraction, double /*now_s*/) {
  std::lock_guard lock(mutex_);
  if (!(fraction >= 0.0)) fraction = 0.0;  // NaN too
  fraction = std::clamp(fraction, fraction_, 1.0);
  if (fraction != fraction_) news_ = true;
  fraction_ = fraction;
}

void ProgressDisplay::set_phase(std::string_view name) {
  std::lock_guard lock(mutex_);
  if (phase_ == name) return;
  phase_ = std::string(name);
  news_ = true;
}

std::optional<std::string> ProgressDisplay::due(double now_s) {
  std::lock_guard lock(mutex_);
  if (now_s < first_draw_s && fraction_ < 1.0) return std::nullopt;
  if (drawn_) {
    const double since = now_s - last_draw_s_;
    if (since < min_interval_s) return std::nullopt;
    if (!news_ && since < max_interval_s) return std::nullopt;
  }
  drawn_ = true;
  news_ = false;
  last_draw_s_ = now_s;
  return line_locked(now_s);
}

std::string ProgressDisplay::line(double now_s) const {
  std::lock_guard lock(mutex_);
  return line_locked(now_s);
}

std::string ProgressDisplay::line_locked(double now_s) const {
  constexpr int width = 24;
  const int filled = static_cast<int>(fraction_ * width);
  std::string out = fmt::format("{:<18} [{}{}] {:3.0f}%  {:.1f} s  {}", label_, std::string(std::size_t(filled), '#'),
                                std::string(std::size_t(width - filled), '.'), 100.0 * fraction_, now_s,
                                fraction_ < 1.0 ? time_left_text(fraction_, now_s) : std::string("done"));
  if (!phase_.empty()) {
    constexpr std::size_t longest = 28;
    out += "  " + (phase_.size() > longest ? phase_.substr(0, longest - 3) + "..." : phase_);
  }
  return out;
}

std::string ProgressDisplay::time_left_text(double fraction, double elapsed_s) {
  if (!(fraction >= 0.02) || elapsed_s < 2.0 || fraction >= 1.0) return "estimating";
  const double left = elapsed_s * (1.0 - fraction) / fraction;  // the average rate so far
  const long s = std::lround(left);
  if (s < 60) return fmt::format("~{} s left", std::max(1L, s));
  if (s < 3600) return fmt::format("~{} min {:02} s left", s / 60, s % 60);
  return fmt::format("~{} h {:02} min left", s / 3600, (s % 3600) / 60);
}

}  // namespace pointsurf::cli
