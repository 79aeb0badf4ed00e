// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "clean/detail/clean_common.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

// The scale of a MAD as a standard deviation for normally distributed values.
constexpr double kMadToSigma = 1.4826;

// Median of `values` (reordered); 0 when empty.
double median_of(std::span<double> values) {
  if (values.empty()) return 0.0;
  const auto middle = values.begin() + std::ptrdiff_t(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace

const FieldTable<LocalOutlierParams>& LocalOutlierParams::fields() {
  static const FieldTable<LocalOutlierParams> table = [] {
    using P = LocalOutlierParams;
    constexpr double inf = std::numeric_limits<double>::infinity();
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point, the point excluded").at_least(2).unit("points");
    t.number("min_ratio", &P::min_ratio, "Drop only points whose mean neighbour distance is above this many times their neighbours'")
        .range(1.0, inf, true, false);
    t.number("mad_sigmas", &P::mad_sigmas, "... and above the median ratio by this many robust standard deviations").positive();
    t.number("far_ratio", &P::far_ratio, "Also drop points whose mean neighbour distance is above this many times the cloud's median")
        .range(1.0, inf, true, false);
    return t;
  }();
  return table;
}

void LocalOutlierParams::validate() const { fields().validate(*this, "remove_local_outliers"); }

OutlierResult remove_local_outliers(const PointCloud& cloud, const LocalOutlierParams& params, const KdTree* tree,
                                    const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_local_outliers";
  params.validate();
  const std::size_t k = static_cast<std::size_t>(params.k);
  detail::check_cloud(fn, cloud, k + 1, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const std::size_t n = cloud.size();

  // 1. Mean distance to the k nearest others, and who they are.
  std::vector<double> mean_distance(n);
  std::vector<std::uint32_t> neighbour_of(n * k);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, 2 * n);
  detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.knn(cloud.positions[i], k + 1, neighbors);
    // The point itself is normally first, but among duplicates another may precede it: skip it
    // wherever it is and keep k others (there are k + 1 points at least).
    std::size_t used = 0;
    double sum = 0.0;
    for (const Neighbor& nb : neighbors) {
      if (nb.index == i || used == k) continue;
      neighbour_of[std::size_t(i) * k + used++] = nb.index;
      sum += std::sqrt(nb.squared_distance);
    }
    for (std::size_t u = used; u < k; ++u) neighbour_of[std::size_t(i) * k + u] = i;
    mean_distance[i] = sum / double(std::max<std::size_t>(used, 1));
  });

  // 2. Ratio to the neighbourhood's median mean distance.
  std::vector<double> ratio(n);
  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::vector<double>& local = scratch.local();
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      local.resize(k);
      for (std::size_t u = 0; u < k; ++u) local[u] = mean_distance[neighbour_of[i * k + u]];
      const double reference = median_of(local);
      ratio[i] = reference > 0.0 ? mean_distance[i] / reference : (mean_distance[i] > 0.0 ? std::numeric_limits<double>::infinity() : 1.0);
    }
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();
  std::vector<std::uint32_t>().swap(neighbour_of);

  // 3. Robust cut over all ratios.
  std::vector<double> sorted = mean_distance;
  const double far = params.far_ratio * median_of(sorted);
  sorted = ratio;
  const double centre = median_of(sorted);
  for (double& v : sorted) v = std::abs(v - centre);
  const double spread = kMadToSigma * median_of(sorted);
  const double threshold = std::max(params.min_ratio, centre + params.mad_sigmas * spread);
  OutlierResult result;
  result.threshold = threshold;
  result.kept.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (!(ratio[i] > threshold) && !(mean_distance[i] > far)) result.kept.push_back(static_cast<std::uint32_t>(i));
  result.removed = n - result.kept.size();
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
