// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/deviation_stats.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

// Equal bins over [lo, hi] (widened around a single value); values outside go to the end bins.
void fill_histogram(std::span<const double> values, std::size_t bins, double lo, double hi, std::vector<double>& edges,
                    std::vector<std::size_t>& counts, std::size_t* below = nullptr, std::size_t* above = nullptr) {
  if (!(hi > lo)) {
    const double half = lo != 0.0 ? 0.5 * std::abs(lo) : 0.5;
    lo -= half;
    hi += half;
  }
  edges.resize(bins + 1);
  for (std::size_t i = 0; i <= bins; ++i) edges[i] = lo + (hi - lo) * static_cast<double>(i) / static_cast<double>(bins);
  counts.assign(bins, 0);
  for (double v : values) {
    const double f = (v - lo) / (hi - lo) * static_cast<double>(bins);
    counts[static_cast<std::size_t>(std::clamp(f, 0.0, static_cast<double>(bins - 1)))]++;
    if (below && v < lo) ++*below;
    if (above && v > hi) ++*above;
  }
}

// The index a full ascending sort would give the nearest-rank percentile `percent` of n > 0 values.
std::size_t percentile_index(std::size_t n, double percent) {
  const double count = static_cast<double>(n);
  return static_cast<std::size_t>(std::clamp(std::ceil(percent / 100.0 * count), 1.0, count)) - 1;
}

// Puts at each of `ranks` the value an ascending sort would put there, by nested selection
// (nth_element at the middle rank, then each side with the ranks that fall in it): O(n log k)
// for k ranks instead of a sort's O(n log n), with the same values (they are order statistics).
void select_ranks(std::span<double> values, std::vector<std::size_t> ranks) {
  std::sort(ranks.begin(), ranks.end());
  ranks.erase(std::unique(ranks.begin(), ranks.end()), ranks.end());
  const auto select = [&](auto& self, std::size_t begin, std::size_t end, std::size_t first_rank, std::size_t last_rank) -> void {
    if (first_rank >= last_rank || end - begin < 2) return;
    const std::size_t middle = first_rank + (last_rank - first_rank) / 2;
    const std::size_t at = ranks[middle];
    std::nth_element(values.begin() + static_cast<std::ptrdiff_t>(begin), values.begin() + static_cast<std::ptrdiff_t>(at),
                     values.begin() + static_cast<std::ptrdiff_t>(end));
    self(self, begin, at, first_rank, middle);
    self(self, at + 1, end, middle + 1, last_rank);
  };
  select(select, 0, values.size(), 0, ranks.size());
}

}  // namespace

double percentile_of_sorted(std::span<const double> sorted, double percent) {
  if (sorted.empty()) return 0.0;
  return sorted[percentile_index(sorted.size(), percent)];
}

ValueDistribution distribution_of(std::vector<double> values, std::size_t bins, double lo, double hi) {
  ValueDistribution d;
  if (values.empty() || bins == 0) return d;
  double sum = 0.0;
  for (double v : values) sum += v;
  d.mean = sum / static_cast<double>(values.size());
  const std::size_t n = values.size();
  select_ranks(values, {0, n - 1, percentile_index(n, 5), percentile_index(n, 50), percentile_index(n, 95)});
  d.min = values.front();
  d.max = values.back();
  d.p05 = values[percentile_index(n, 5)];
  d.p50 = values[percentile_index(n, 50)];
  d.p95 = values[percentile_index(n, 95)];
  if (!(hi > lo)) {
    lo = d.min;
    hi = d.max;
  }
  fill_histogram(values, bins, lo, hi, d.edges, d.counts);
  return d;
}

const FieldTable<DeviationParams>& DeviationParams::fields() {
  static const FieldTable<DeviationParams> table = [] {
    using P = DeviationParams;
    FieldTable<P> t;
    t.number("tolerance", &P::tolerance, "Share within +-tolerance is reported; 0: not reported").unit("cloud units").non_negative().meta("T");
    t.integer("bins", &P::bins, "Histogram bins; 0: from the data").range(0, 10000);
    t.number("histogram_min", &P::histogram_min, "Histogram's lower edge; both 0: the data's range").unit("cloud units").internal();
    t.number("histogram_max", &P::histogram_max, "Histogram's upper edge; both 0: the data's range").unit("cloud units").internal();
    t.numbers("percentiles", &P::percentiles, "Percentiles of the signed deviation")
        .unit("percent")
        .range(0, 100)
        .when([](const P& p) { return !p.percentiles.empty(); });
    return t;
  }();
  return table;
}

void DeviationParams::validate() const {
  if (histogram_max < histogram_min)
    throw UsageError(fmt::format("summarize_deviation: histogram_max {} is below histogram_min {}", histogram_max, histogram_min));
  fields().validate(*this, "summarize_deviation");
}

DeviationStats summarize_deviation(std::span<const double> deviations, const DeviationParams& params) {
  params.validate();
  DeviationStats s;
  s.tolerance = params.tolerance;
  std::vector<double> values;
  values.reserve(deviations.size());
  for (double d : deviations) {
    if (std::isfinite(d)) values.push_back(d);
    else ++s.ignored;
  }
  s.count = values.size();
  s.percentile_ranks = params.percentiles;
  if (values.empty()) {
    s.percentile_values.assign(params.percentiles.size(), 0.0);
    return s;
  }
  // Sums about the first value keep the standard deviation accurate for offset data.
  double sum = 0.0, sum_abs = 0.0, sum_sq = 0.0, sum_pos = 0.0, sum_neg = 0.0;
  std::size_t within = 0;
  for (double d : values) {
    sum += d;
    sum_abs += std::abs(d);
    sum_sq += d * d;
    if (d > 0.0) {
      ++s.positive;
      sum_pos += d;
      s.max_positive = std::max(s.max_positive, d);
    } else if (d < 0.0) {
      ++s.negative;
      sum_neg += d;
      s.max_negative = std::min(s.max_negative, d);
    }
    if (std::abs(d) <= params.tolerance) ++within;
  }
  const double n = static_cast<double>(s.count);
  s.mean = sum / n;
  s.mean_absolute = sum_abs / n;
  s.rms = std::sqrt(sum_sq / n);
  double centred = 0.0;
  for (double d : values) centred += (d - s.mean) * (d - s.mean);
  s.std = std::sqrt(centred / n);
  s.mean_positive = s.positive > 0 ? sum_pos / static_cast<double>(s.positive) : 0.0;
  s.mean_negative = s.negative > 0 ? sum_neg / static_cast<double>(s.negative) : 0.0;
  s.within_tolerance = params.tolerance > 0.0 ? static_cast<double>(within) / n : 0.0;
  if (params.tolerance > 0.0) {
    std::size_t above = 0, below = 0;
    for (double d : values) {
      above += d > params.tolerance ? 1 : 0;
      below += d < -params.tolerance ? 1 : 0;
    }
    s.above_tolerance = static_cast<double>(above) / n;
    s.below_tolerance = static_cast<double>(below) / n;
    s.out_of_tolerance = static_cast<double>(above + below) / n;
  }
  // Order statistics by selection, not sorting: the same values, several times faster.
  const std::size_t count = values.size();
  const std::size_t q1 = std::size_t(0.25 * (n - 1)), q3 = std::size_t(0.75 * (n - 1));
  std::vector<std::size_t> ranks = {0, count - 1, percentile_index(count, 0.5), percentile_index(count, 99.5), q1, q3};
  for (double p : params.percentiles) ranks.push_back(percentile_index(count, p));
  std::vector<double> magnitudes(values.size());
  std::transform(values.begin(), values.end(), magnitudes.begin(), [](double d) { return std::abs(d); });
  tbb::parallel_invoke([&] { select_ranks(magnitudes, {percentile_index(count, 95.0), percentile_index(count, 99.0)}); },
                       [&] { select_ranks(values, ranks); });
  s.abs_p95 = magnitudes[percentile_index(count, 95.0)];
  s.abs_p99 = magnitudes[percentile_index(count, 99.0)];
  magnitudes = {};

  for (double p : params.percentiles) s.percentile_values.push_back(values[percentile_index(count, p)]);
  double lo = params.histogram_min, hi = params.histogram_max;
  if (!(hi > lo)) {
    // The robust range, widened to show the tolerance band, within the data's extremes.
    lo = std::max(values.front(), std::min(values[percentile_index(count, 0.5)], -params.tolerance));
    hi = std::min(values.back(), std::max(values[percentile_index(count, 99.5)], params.tolerance));
  }
  std::size_t bins = params.bins;
  if (bins == 0) {
    // Freedman-Diaconis: width 2 IQR / cbrt(n), clamped to 10..200 bins.
    const double iqr = values[q3] - values[q1];
    const double width = 2.0 * iqr / std::cbrt(n);
    const double wanted = width > 0.0 ? std::ceil((hi - lo) / width) : 10.0;
    bins = static_cast<std::size_t>(std::clamp(std::isfinite(wanted) ? wanted : 10.0, 10.0, 200.0));
  }
  fill_histogram(values, bins, lo, hi, s.histogram_edges, s.histogram_counts, &s.histogram_below, &s.histogram_above);
  return s;
}

std::vector<RegionDeviation> summarize_deviation_by_region(std::span<const double> deviations, std::span<const double> labels,
                                                           const DeviationParams& params) {
  if (labels.size() != deviations.size())
    throw InputError(fmt::format("{} labels for {} deviations", labels.size(), deviations.size()));
  std::map<long, std::vector<double>> groups;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (!std::isfinite(labels[i])) throw InputError(fmt::format("label of point {} is not finite", i));
    groups[std::lround(labels[i])].push_back(deviations[i]);
  }
  std::vector<RegionDeviation> out;
  for (const auto& [label, values] : groups) out.push_back({label, summarize_deviation(values, params)});
  return out;
}

const ResultTable<DeviationStats>& DeviationStats::results() {
  static const ResultTable<DeviationStats> table = [] {
    using D = DeviationStats;
    const std::string u = "cloud units";
    ResultTable<D> t;
    t.count("count", &D::count, "Finite deviations summarised").in_headline();
    // What a reader looks at first: how much is out of tolerance, then robust and extreme sizes.
    t.number("out_of_tolerance", &D::out_of_tolerance, "Share (0..1) of deviations beyond the tolerance, either side (0 without one)")
        .lower_is_better()
        .in_headline();
    t.number("above_tolerance", &D::above_tolerance, "Share (0..1) of deviations above +tolerance").lower_is_better().in_headline();
    t.number("below_tolerance", &D::below_tolerance, "Share (0..1) of deviations below -tolerance").lower_is_better().in_headline();
    t.number("tolerance", &D::tolerance, "The tolerance band, as given").with_unit(u).in_headline();
    t.number("within_tolerance", &D::within_tolerance, "Share (0..1) of deviations within the tolerance").higher_is_better().in_headline();
    t.number("abs_p95", &D::abs_p95, "95th percentile of |deviation|: robust beside the maxima").with_unit(u).lower_is_better().in_headline();
    t.number("abs_p99", &D::abs_p99, "99th percentile of |deviation|: robust beside the maxima").with_unit(u).lower_is_better().in_headline();
    t.number("max_positive", &D::max_positive, "Largest deviation above the surface (0 when none)").with_unit(u).lower_is_better().in_headline();
    t.number("max_negative", &D::max_negative, "Most negative deviation, below the surface (0 when none)").with_unit(u).higher_is_better().in_headline();
    t.number("mean_positive", &D::mean_positive, "Mean of the deviations above the surface").with_unit(u).lower_is_better().in_headline();
    t.number("mean_negative", &D::mean_negative, "Mean of the deviations below the surface").with_unit(u).higher_is_better().in_headline();
    t.number("mean", &D::mean, "Signed mean deviation").with_unit(u).in_headline();
    t.number("mean_absolute", &D::mean_absolute, "Mean absolute deviation").with_unit(u).lower_is_better().in_headline();
    t.number("rms", &D::rms, "Root mean square deviation").with_unit(u).lower_is_better().in_headline();
    t.number("std", &D::std, "Standard deviation about the mean").with_unit(u).lower_is_better().in_headline();
    t.count("positive", &D::positive, "Deviations above the surface");
    t.count("negative", &D::negative, "Deviations below the surface");
    t.count("ignored", &D::ignored, "Non-finite deviations left out (beyond a distance limit)").lower_is_better();
    t.family(
         "percentiles/p*", ResultType::Number,
         [](const D& d) {
           std::vector<std::pair<std::string, ResultValue>> out;
           for (std::size_t i = 0; i < d.percentile_ranks.size() && i < d.percentile_values.size(); ++i) {
             std::string rank = format_value(d.percentile_ranks[i]);
             std::replace(rank.begin(), rank.end(), '.', '_');
             out.emplace_back(rank, d.percentile_values[i]);
           }
           return out;
         },
         "Nearest-rank percentile of the deviations, one per rank asked (p99_9: 99.9 %)")
        .with_unit(u);
    t.numbers("histogram/edges", &D::histogram_edges, "Histogram bin edges (bins + 1)").with_unit(u);
    t.numbers("histogram/counts", &D::histogram_counts, "Deviations per bin; values outside the edges in the end bins");
    t.count("histogram/below", &D::histogram_below, "Deviations below the first edge, counted in the first bin");
    t.count("histogram/above", &D::histogram_above, "Deviations above the last edge, counted in the last bin");
    return t;
  }();
  return table;
}

const ResultTable<ValueDistribution>& ValueDistribution::results() {
  static const ResultTable<ValueDistribution> table = [] {
    using V = ValueDistribution;
    ResultTable<V> t;
    t.number("min", &V::min, "Smallest value");
    t.number("max", &V::max, "Largest value");
    t.number("mean", &V::mean, "Mean value");
    t.number("p05", &V::p05, "5th percentile (nearest rank)");
    t.number("p50", &V::p50, "Median (nearest rank)");
    t.number("p95", &V::p95, "95th percentile (nearest rank)");
    t.numbers("histogram/edges", &V::edges, "Histogram bin edges (bins + 1)");
    t.numbers("histogram/counts", &V::counts, "Values per bin; values outside the edges in the end bins");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
