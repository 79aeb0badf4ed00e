// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A length parameter: a value in cloud units or in spacings of the cloud, one field where
// pointsurf used to carry a pair (radius and radius_in_spacings, 0 meaning "use the other").
//
//   NormalParams p;
//   p.radius = Length::cloud(0.05);     // 5 cm on a cloud in metres
//   p.radius = Length::spacings(3);     // 3 mean spacings, whatever the cloud's scale
//   double r = p.radius.resolve(mean_spacing(tree));
//
// As text (the command line, pipelines, Python): "0.05" is in cloud units, "3sp" in spacings.
#include <string>
#include <string_view>

namespace pointsurf {

struct Length {
  enum class Unit { Cloud, Spacings };

  double value = 0.0;
  Unit unit = Unit::Cloud;

  static constexpr Length cloud(double v) noexcept { return {v, Unit::Cloud}; }
  static constexpr Length spacings(double v) noexcept { return {v, Unit::Spacings}; }

  bool in_spacings() const noexcept { return unit == Unit::Spacings; }
  /// The length in cloud units: `value`, or `value` x `spacing` (the spacing the algorithm
  /// measures: the cloud's mean spacing unless its doc says local spacing).
  double resolve(double spacing) const noexcept { return unit == Unit::Spacings ? value * spacing : value; }

  /// "0.05" or "3sp", numbers in the shortest form that reads back exactly.
  std::string text() const;
  /// Parses "0.05", "3sp", "3 sp", "3spacings"; throws UsageError naming `key` otherwise or for a
  /// value that is not finite.
  static Length parse(std::string_view text, std::string_view key);

  friend bool operator==(const Length&, const Length&) = default;
};

}  // namespace pointsurf
