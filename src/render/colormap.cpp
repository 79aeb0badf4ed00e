// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/render/colormap.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pointsurf {
namespace {

struct Stop {
  double t, r, g, b;
};

// Viridis (van der Walt and Smith, matplotlib), 9 stops of the published table.
constexpr Stop kViridis[] = {{0.000, 0.267, 0.005, 0.329}, {0.125, 0.283, 0.141, 0.458}, {0.250, 0.254, 0.265, 0.530},
                             {0.375, 0.207, 0.372, 0.553}, {0.500, 0.164, 0.471, 0.558}, {0.625, 0.128, 0.567, 0.551},
                             {0.750, 0.135, 0.659, 0.518}, {0.875, 0.267, 0.749, 0.441}, {1.000, 0.993, 0.906, 0.144}};
// Cool-warm (Moreland 2009): blue, near-white at the middle, red.
constexpr Stop kCoolWarm[] = {{0.000, 0.230, 0.299, 0.754}, {0.125, 0.348, 0.466, 0.888}, {0.250, 0.484, 0.622, 0.975},
                              {0.375, 0.619, 0.744, 0.999}, {0.500, 0.865, 0.865, 0.865}, {0.625, 0.958, 0.747, 0.652},
                              {0.750, 0.968, 0.617, 0.484}, {0.875, 0.887, 0.413, 0.324}, {1.000, 0.706, 0.016, 0.150}};

template <std::size_t N>
std::array<std::uint8_t, 3> lookup(const Stop (&stops)[N], double t) {
  t = std::clamp(t, 0.0, 1.0);
  std::size_t i = 1;
  while (i + 1 < N && stops[i].t < t) ++i;
  const Stop& a = stops[i - 1];
  const Stop& b = stops[i];
  const double f = (t - a.t) / (b.t - a.t);
  auto channel = [f](double x, double y) { return static_cast<std::uint8_t>(std::lround(255.0 * (x + f * (y - x)))); };
  return {channel(a.r, b.r), channel(a.g, b.g), channel(a.b, b.b)};
}

}  // namespace

double ColorScale::low() const noexcept { return kind == ColorMapKind::Diverging ? -std::max(std::abs(min), std::abs(max)) : min; }
double ColorScale::high() const noexcept { return kind == ColorMapKind::Diverging ? std::max(std::abs(min), std::abs(max)) : max; }

std::array<std::uint8_t, 3> ColorScale::color(double value) const noexcept {
  if (!std::isfinite(value)) return {128, 128, 128};
  if (out_of_range && value > high()) return kOverRange;
  if (out_of_range && value < low()) return kUnderRange;
  if (kind == ColorMapKind::Diverging) {
    if (tolerance > 0.0 && std::abs(value) <= tolerance) return {64, 176, 72};
    const double half = high();
    return lookup(kCoolWarm, half > 0.0 ? 0.5 + 0.5 * value / half : 0.5);
  }
  return lookup(kViridis, max > min ? (value - min) / (max - min) : 0.5);
}

ColorScale default_color_scale(std::span<const double> values, const std::string& field_name, bool diverging, double tolerance) {
  ColorScale s;
  const bool signed_field = diverging || field_name == "deviation" || field_name.rfind("distance", 0) == 0;
  std::vector<double> finite;
  finite.reserve(values.size());
  for (double v : values)
    if (std::isfinite(v)) finite.push_back(signed_field ? std::abs(v) : v);
  if (signed_field) {
    s.kind = ColorMapKind::Diverging;
    s.out_of_range = true;
    s.tolerance = tolerance;
    double half = 0.0;
    if (finite.size() >= 1000) {  // nearest rank, as the deviation statistics' abs_p99
      const auto k = static_cast<std::ptrdiff_t>(std::ceil(0.99 * static_cast<double>(finite.size()))) - 1;
      std::nth_element(finite.begin(), finite.begin() + k, finite.end());
      half = finite[static_cast<std::size_t>(k)];
    } else {
      for (double v : finite) half = std::max(half, v);
    }
    half = std::max(half, 2.0 * tolerance);
    if (half == 0.0) half = 1.0;
    s.min = -half;
    s.max = half;
    return s;
  }
  if (finite.empty()) return s;
  auto rank = [&](double q) {
    const std::size_t k = std::min(finite.size() - 1, static_cast<std::size_t>(q * double(finite.size() - 1) + 0.5));
    std::nth_element(finite.begin(), finite.begin() + std::ptrdiff_t(k), finite.end());
    return finite[k];
  };
  // Small fields (a label, a class) keep their full range; large ones drop 1% at each end.
  const bool robust = finite.size() >= 1000;
  s.min = robust ? rank(0.01) : *std::min_element(finite.begin(), finite.end());
  s.max = robust ? rank(0.99) : *std::max_element(finite.begin(), finite.end());
  if (!(s.max > s.min)) {
    s.min -= 0.5;
    s.max += 0.5;
  }
  return s;
}

}  // namespace pointsurf
