// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Deviation statistics like the commercial reports (Geomagic Control, ImageWare): the extreme
// and mean deviation on each side, RMS, standard deviation, histogram, share within tolerance,
// percentiles, and the same per region when points carry a segment or region label.
#include <cstddef>
#include <span>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/results.h"

namespace pointsurf {

struct DeviationParams {
  double tolerance = 0.0;            // cloud units; within_tolerance counts |d| <= tolerance; 0: not reported
  std::size_t bins = 0;              // histogram bins; 0: from the data (Freedman-Diaconis, 10..200)
  /// Both 0: the robust range, from the 0.5th to the 99.5th percentile widened to +-tolerance
  /// (never past the data's extremes), so a few outliers do not squeeze the bins; the values
  /// beyond it are counted in the end bins (histogram_below, histogram_above).
  double histogram_min = 0.0;        // cloud units
  double histogram_max = 0.0;
  std::vector<double> percentiles = {1, 5, 25, 50, 75, 95, 99};  // in percent, of the signed values
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<DeviationParams>& fields();
  /// Throws UsageError for a negative tolerance, percentiles outside [0, 100] or
  /// histogram_max < histogram_min.
  void validate() const;
};

struct DeviationStats {
  std::size_t count = 0;             // finite values summarised
  std::size_t positive = 0, negative = 0;  // values > 0 and < 0
  std::size_t ignored = 0;           // infinite or NaN values left out (beyond a distance limit)
  double max_positive = 0.0;         // largest value > 0 (0 when none); cloud units, smaller is better
  double max_negative = 0.0;         // most negative value (<= 0; 0 when none)
  double mean_positive = 0.0;        // mean of the values > 0
  double mean_negative = 0.0;        // mean of the values < 0 (<= 0)
  double mean = 0.0;                 // signed mean
  double mean_absolute = 0.0;
  double rms = 0.0;                  // sqrt(mean d^2)
  double std = 0.0;                  // standard deviation about the mean (population)
  double tolerance = 0.0;            // as given
  double within_tolerance = 0.0;     // share (0..1) of values with |d| <= tolerance; larger is better
  double out_of_tolerance = 0.0;     // share (0..1) with |d| > tolerance (0 without a tolerance)
  double above_tolerance = 0.0;      // share with d > tolerance
  double below_tolerance = 0.0;      // share with d < -tolerance
  double abs_p95 = 0.0, abs_p99 = 0.0;  // nearest-rank percentiles of |d|: robust beside the maxima
  std::vector<double> percentile_ranks;   // percent, as asked
  std::vector<double> percentile_values;  // nearest-rank percentiles, cloud units
  std::vector<double> histogram_edges;    // bins + 1; by default over the robust range (below)
  std::vector<std::size_t> histogram_counts;  // bins; values outside the edges go to the end bins
  std::size_t histogram_below = 0, histogram_above = 0;  // values beyond the edges, counted in the end bins

  /// The reported members: key, unit, which way is better, doc (core/results.h).
  static const ResultTable<DeviationStats>& results();
};

struct RegionDeviation {
  long label = 0;                    // the region's value of the label field
  DeviationStats stats;
};

/// A distribution of values (triangle angles, aspect ratios).
struct ValueDistribution {
  double min = 0.0, max = 0.0, mean = 0.0;
  double p05 = 0.0, p50 = 0.0, p95 = 0.0;  // percentiles (nearest rank)
  std::vector<double> edges;               // histogram bin edges (bins + 1)
  std::vector<std::size_t> counts;         // values per bin (bins); values outside go to the end bins

  /// The reported members (core/results.h); `unit` is the values' unit.
  static const ResultTable<ValueDistribution>& results();
};

/// Summary of `values` (any order) with `bins` equal bins over [lo, hi]; lo == hi: over the
/// data's range. Empty values give zeros.
ValueDistribution distribution_of(std::vector<double> values, std::size_t bins, double lo = 0.0, double hi = 0.0);

/// The nearest-rank percentile `percent` (0..100) of ascending `sorted` values (0 when empty).
double percentile_of_sorted(std::span<const double> sorted, double percent);

/// Statistics of `deviations` (cloud units, signed). Non-finite values are counted in `ignored`.
/// Throws UsageError for a negative tolerance, percentiles outside [0, 100] or
/// histogram_max < histogram_min. O(N log k) for k percentiles (selection, no sort); thread-safe.
DeviationStats summarize_deviation(std::span<const double> deviations, const DeviationParams& params = {});

/// The statistics per value of `labels` (one per deviation; regions in increasing label order).
/// Throws InputError when the sizes differ.
std::vector<RegionDeviation> summarize_deviation_by_region(std::span<const double> deviations, std::span<const double> labels,
                                                           const DeviationParams& params = {});

}  // namespace pointsurf
