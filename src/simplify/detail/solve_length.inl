// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <cmath>
#include <cstdlib>
#include <utility>

namespace pointsurf::detail {

template <typename CountFn>
std::pair<double, std::size_t> solve_length(double initial, std::size_t wanted, double tolerance, int max_steps, CountFn&& count) {
  const double target = std::log(double(wanted));
  double l0 = initial;
  std::size_t c0 = count(l0);
  std::pair<double, std::size_t> best{l0, c0};
  auto error = [&](std::size_t c) { return std::abs(double(c) - double(wanted)) / double(wanted); };
  if (error(c0) <= tolerance) return best;
  // First step assumes a surface (count ~ L^-2); later steps use the measured slope.
  double slope = -2.0;
  double l1 = l0 * std::exp((std::log(double(std::max<std::size_t>(c0, 1))) - target) / -slope);
  for (int step = 0; step < max_steps; ++step) {
    const std::size_t c1 = count(l1);
    if (error(c1) < error(best.second)) best = {l1, c1};
    if (error(c1) <= tolerance) break;
    const double dl = std::log(l1) - std::log(l0);
    const double dc = std::log(double(std::max<std::size_t>(c1, 1))) - std::log(double(std::max<std::size_t>(c0, 1)));
    // Keep the slope in a plausible range (curves: -1, surfaces: -2, volumes: -3); a flat or
    // positive measured slope comes from a count that cannot move (every point its own cell).
    if (std::abs(dl) > 1e-12 && dc != 0.0) slope = std::clamp(dc / dl, -4.0, -0.5);
    l0 = l1;
    c0 = c1;
    const double next = l1 * std::exp((std::log(double(std::max<std::size_t>(c1, 1))) - target) / -slope);
    if (!(next > 0.0) || !std::isfinite(next) || std::abs(next - l1) <= 1e-9 * l1) break;
    l1 = next;
  }
  return best;
}

}  // namespace pointsurf::detail
