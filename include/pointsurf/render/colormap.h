// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Colour maps for scalar fields: sequential (viridis) for magnitudes, diverging (blue, white,
// red; Moreland's cool-warm) for signed deviations, with an optional tolerance band drawn in
// green as deviation reports (Geomagic, ImageWare) do.
#include <array>
#include <cstdint>
#include <span>
#include <string>

namespace pointsurf {

enum class ColorMapKind { Sequential, Diverging };

/// How values become colours: `min`..`max` spans the map; values outside are clamped. For a
/// diverging map, zero is white and |value| <= `tolerance` (when > 0) is green.
struct ColorScale {
  ColorMapKind kind = ColorMapKind::Sequential;
  double min = 0.0, max = 1.0;  // field units
  double tolerance = 0.0;       // field units; diverging only; 0: no band
  std::string unit;             // shown on the legend ("m", "mm", "" for none)

  /// RGB in 0..255 of `value`; NaN and infinite values are grey.
  std::array<std::uint8_t, 3> color(double value) const noexcept;
};

/// The scale a field gets by default: diverging and symmetric about 0 (max |value|) when the
/// field is named "deviation" or "distance*", or when `diverging`; else sequential between
/// the 1st and 99th percentile (so a few outliers do not wash the map out). Ignores NaN and
/// infinite values; an empty or constant field gets a unit-wide range.
ColorScale default_color_scale(std::span<const double> values, const std::string& field_name, bool diverging = false);

}  // namespace pointsurf
