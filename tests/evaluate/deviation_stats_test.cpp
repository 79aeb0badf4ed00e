// SPDX-License-Identifier: GPL-3.0-or-later
// Deviation statistics on values whose answers are worked out by hand, the histogram, the
// per-region breakdown and the error paths.
#include "pointsurf/evaluate/deviation_stats.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

TEST(DeviationStats, HandWorkedValues) {
  const std::vector<double> d = {-2, -1, 0, 1, 2, 3, std::numeric_limits<double>::infinity()};
  DeviationParams p;
  p.tolerance = 1.0;
  p.percentiles = {0, 50, 100};
  const DeviationStats s = summarize_deviation(d, p);
  EXPECT_EQ(s.count, 6u);
  EXPECT_EQ(s.ignored, 1u);
  EXPECT_EQ(s.positive, 3u);
  EXPECT_EQ(s.negative, 2u);
  EXPECT_DOUBLE_EQ(s.max_positive, 3.0);
  EXPECT_DOUBLE_EQ(s.max_negative, -2.0);
  EXPECT_DOUBLE_EQ(s.mean_positive, 2.0);
  EXPECT_DOUBLE_EQ(s.mean_negative, -1.5);
  EXPECT_DOUBLE_EQ(s.mean, 0.5);
  EXPECT_DOUBLE_EQ(s.mean_absolute, 1.5);
  EXPECT_DOUBLE_EQ(s.rms, std::sqrt(19.0 / 6.0));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(19.0 / 6.0 - 0.25));
  EXPECT_DOUBLE_EQ(s.within_tolerance, 0.5);  // -1, 0, 1
  ASSERT_EQ(s.percentile_values.size(), 3u);
  EXPECT_DOUBLE_EQ(s.percentile_values[0], -2.0);
  EXPECT_DOUBLE_EQ(s.percentile_values[1], 0.0);
  EXPECT_DOUBLE_EQ(s.percentile_values[2], 3.0);
  EXPECT_EQ(std::accumulate(s.histogram_counts.begin(), s.histogram_counts.end(), std::size_t(0)), 6u);
  EXPECT_EQ(s.histogram_edges.size(), s.histogram_counts.size() + 1);
  EXPECT_DOUBLE_EQ(s.histogram_edges.front(), -2.0);
  EXPECT_DOUBLE_EQ(s.histogram_edges.back(), 3.0);
}

TEST(DeviationStats, GivenBinsAndRangeAreKept) {
  const std::vector<double> d = {-0.9, -0.1, 0.1, 0.2, 0.6, 5.0};
  DeviationParams p;
  p.bins = 4;
  p.histogram_min = -1.0;
  p.histogram_max = 1.0;
  const DeviationStats s = summarize_deviation(d, p);
  ASSERT_EQ(s.histogram_counts.size(), 4u);
  EXPECT_EQ(s.histogram_counts, (std::vector<std::size_t>{1, 1, 2, 2}));  // 5.0 goes to the last bin
  EXPECT_DOUBLE_EQ(s.histogram_edges[2], 0.0);
  EXPECT_EQ(s.histogram_above, 1u);
  EXPECT_EQ(s.histogram_below, 0u);
}

// Shares out of tolerance on each side and the robust |d| percentiles, counted by hand: 100
// values 0.01 .. 1.00 with the signs alternating, tolerance 0.5.
TEST(DeviationStats, SharesOutOfToleranceAndRobustMagnitudes) {
  std::vector<double> d;
  for (int i = 1; i <= 100; ++i) d.push_back((i % 2 ? 1.0 : -1.0) * 0.01 * i);
  const DeviationStats s = summarize_deviation(d, {.tolerance = 0.5});
  EXPECT_DOUBLE_EQ(s.within_tolerance, 0.5);    // 0.01 .. 0.50
  EXPECT_DOUBLE_EQ(s.out_of_tolerance, 0.5);
  EXPECT_DOUBLE_EQ(s.above_tolerance, 0.25);    // odd i in 51..99
  EXPECT_DOUBLE_EQ(s.below_tolerance, 0.25);    // even i in 52..100
  EXPECT_DOUBLE_EQ(s.abs_p95, 0.95);
  EXPECT_DOUBLE_EQ(s.abs_p99, 0.99);
  const DeviationStats untoleranced = summarize_deviation(d);
  EXPECT_DOUBLE_EQ(untoleranced.out_of_tolerance, 0.0);  // no tolerance: nothing is judged
}

// A few far outliers do not squeeze the histogram: its bins cover the robust range (0.5th to
// 99.5th percentile, widened to +-tolerance) and the outliers are counted in the end bins.
TEST(DeviationStats, HistogramCoversTheRobustRangeWithTailsInTheEndBins) {
  std::vector<double> d;
  for (int i = 0; i < 10000; ++i) d.push_back(0.01 * std::sin(0.7 * i));  // within +-0.01
  for (int i = 0; i < 10; ++i) d.push_back(i % 2 ? 5.0 : -3.0);
  const DeviationStats s = summarize_deviation(d, {.tolerance = 0.002});
  EXPECT_GE(s.histogram_edges.front(), -0.0101);
  EXPECT_LE(s.histogram_edges.back(), 0.0101);
  EXPECT_LT(s.histogram_edges.front(), -0.0099);
  EXPECT_GT(s.histogram_edges.back(), 0.0099);
  const auto beyond = [&](auto outside) { return static_cast<std::size_t>(std::count_if(d.begin(), d.end(), outside)); };
  EXPECT_EQ(s.histogram_below, beyond([&](double v) { return v < s.histogram_edges.front(); }));
  EXPECT_EQ(s.histogram_above, beyond([&](double v) { return v > s.histogram_edges.back(); }));
  EXPECT_GE(s.histogram_below, 5u);  // the outliers, and at most 0.5 % of the values
  EXPECT_LE(s.histogram_below, d.size() / 200 + 1);
  EXPECT_EQ(std::accumulate(s.histogram_counts.begin(), s.histogram_counts.end(), std::size_t(0)), d.size());
  EXPECT_GE(s.histogram_counts.front(), 5u);
  EXPECT_GE(s.histogram_counts.back(), 5u);
  // Narrow data and a wide tolerance: the bins reach out to the band, but not past the data.
  const DeviationStats wide = summarize_deviation(std::vector<double>{-0.001, 0.0, 0.002}, {.tolerance = 1.0});
  EXPECT_DOUBLE_EQ(wide.histogram_edges.front(), -0.001);
  EXPECT_DOUBLE_EQ(wide.histogram_edges.back(), 0.002);
}

TEST(DeviationStats, ConstantAndEmptyInputGiveDefinedNumbers) {
  const std::vector<double> same(10, 0.25);
  const DeviationStats s = summarize_deviation(same);
  EXPECT_DOUBLE_EQ(s.std, 0.0);
  EXPECT_DOUBLE_EQ(s.rms, 0.25);
  EXPECT_LT(s.histogram_edges.front(), 0.25);
  EXPECT_GT(s.histogram_edges.back(), 0.25);
  const DeviationStats e = summarize_deviation(std::vector<double>{});
  EXPECT_EQ(e.count, 0u);
  EXPECT_DOUBLE_EQ(e.rms, 0.0);
}

TEST(DeviationStats, PerRegionBreakdown) {
  const std::vector<double> d = {1, 2, -1, -3}, labels = {7, 7, 2, 2};
  const std::vector<RegionDeviation> r = summarize_deviation_by_region(d, labels);
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].label, 2);
  EXPECT_DOUBLE_EQ(r[0].stats.max_negative, -3.0);
  EXPECT_DOUBLE_EQ(r[0].stats.max_positive, 0.0);
  EXPECT_EQ(r[1].label, 7);
  EXPECT_DOUBLE_EQ(r[1].stats.mean_positive, 1.5);
  EXPECT_THROW(summarize_deviation_by_region(d, std::vector<double>{1, 2}), InputError);
}

TEST(DeviationStats, BadParametersAreUsageErrors) {
  const std::vector<double> d = {1.0};
  EXPECT_THROW(summarize_deviation(d, {.tolerance = -1.0}), UsageError);
  EXPECT_THROW(summarize_deviation(d, {.percentiles = {101}}), UsageError);
  EXPECT_THROW(summarize_deviation(d, {.histogram_min = 1.0, .histogram_max = 0.0}), UsageError);
}

}  // namespace
}  // namespace pointsurf
