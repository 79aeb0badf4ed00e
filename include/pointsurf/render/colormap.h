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

/// How values become colours: `min`..`max` spans the map. For a diverging map, zero is white,
/// the map is symmetric about it (max(|min|, |max|) at each end) and |value| <= `tolerance`
/// (when > 0) is green. Values beyond the ends are clamped to the end colours, or, with
/// `out_of_range`, drawn in the over- and under-range colours (magenta and teal, which no map
/// uses), as inspection software shows the points a clipped scale leaves out.
struct ColorScale {
  ColorMapKind kind = ColorMapKind::Sequential;
  double min = 0.0, max = 1.0;  // field units
  double tolerance = 0.0;       // field units; diverging only; 0: no band
  bool out_of_range = false;    // values beyond the ends in their own colours instead of clamped
  std::string unit;             // shown on the legend ("m", "mm", "" for none)

  /// RGB in 0..255 of `value`; NaN and infinite values are grey.
  std::array<std::uint8_t, 3> color(double value) const noexcept;
  /// The low and high ends of the map (a diverging map's are -h and +h, h = max(|min|, |max|)).
  double low() const noexcept;
  double high() const noexcept;
  static constexpr std::array<std::uint8_t, 3> kOverRange{214, 0, 214};
  static constexpr std::array<std::uint8_t, 3> kUnderRange{0, 128, 128};
};

/// The scale a field gets by default. Diverging when the field is named "deviation" or
/// "distance*", or when `diverging`: symmetric about 0, its ends at the 99th percentile of
/// |value| (the largest |value| below 1000 values) but at least twice `tolerance`, with
/// out_of_range set, so a few outliers never stretch the map and the points beyond it show in
/// their own colours. Else sequential between the 1st and 99th percentile, clamped. Ignores NaN
/// and infinite values; an empty or constant field gets a unit-wide range.
ColorScale default_color_scale(std::span<const double> values, const std::string& field_name, bool diverging = false,
                               double tolerance = 0.0);

}  // namespace pointsurf
