// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {

const FieldTable<CurvatureDistanceParams>& CurvatureDistanceParams::fields() {
  static const FieldTable<CurvatureDistanceParams> table = [] {
    using P = CurvatureDistanceParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.integer("k", &P::k, "Neighbours for variation when the input has none").at_least(3).unit("points");
    t.number("split_quantile", &P::split_quantile, "Variation quantile splitting high from low").range(0.0, 1.0, true, true);
    t.number("high_to_low_distance", &P::high_to_low_distance, "High-part distance / low-part distance").range(0.0, 1.0, true, false);
    return t;
  }();
  return table;
}

void CurvatureDistanceParams::validate() const { fields().validate(*this, "simplify_curvature_distance"); }

SimplifyResult simplify_curvature_distance(const PointCloud& cloud, const CurvatureDistanceParams& params, const KdTree* tree,
                                           const ProgressCallback& progress) {
  constexpr std::string_view f = "simplify_curvature_distance";
  detail::check_simplify_input(f, cloud, params.target, true);
  params.validate();
  const std::size_t n = cloud.size();
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_or_own(f, cloud, tree, own);
  const std::vector<double> variation =
      detail::surface_properties(cloud, params.k, t, false, detail::sub_progress(progress, 0.0, 0.5)).variation;
  detail::ProgressReporter reporter(progress, 0.5, 1.0, 1);

  // The split: variation above the split_quantile-quantile is "high".
  std::vector<double> sorted(variation);
  const auto at = sorted.begin() + std::ptrdiff_t(std::min(n - 1, static_cast<std::size_t>(params.split_quantile * double(n))));
  std::nth_element(sorted.begin(), at, sorted.end());
  const double split = *at;
  std::vector<char> high(n);
  for (std::size_t i = 0; i < n; ++i) high[i] = variation[i] > split;

  // Greedy Poisson-disk thinning of each part with its own distance, in spatial order.
  const std::span<const std::uint32_t> order = t.spatial_order();
  std::vector<char> removed(n);
  std::vector<std::uint32_t> keep;
  std::size_t kept_high = 0;
  const auto thin = [&](double d_low) {
    std::fill(removed.begin(), removed.end(), 0);
    keep.clear();
    const double d_high = params.high_to_low_distance * d_low;
    detail::poisson_disk(
        t, cloud.positions, order, removed, keep, [&](std::uint32_t i) { return high[i] ? d_high : d_low; },
        [&](std::uint32_t i, std::uint32_t j) { return high[j] == high[i]; });
    kept_high = std::size_t(std::count_if(keep.begin(), keep.end(), [&](std::uint32_t i) { return high[i] != 0; }));
    return keep.size();
  };
  double d_low = params.target.cell;
  if (d_low == 0.0) {
    const std::size_t wanted = detail::target_count(params.target, n);
    double spacing = mean_spacing(t);
    if (!(spacing > 0.0)) spacing = 1.0;
    d_low = detail::solve_length(spacing * std::sqrt(double(n) / double(wanted)), wanted, 0.01, 8, [&](double d) {
              reporter.report(0.5);
              reporter.throw_if_cancelled();
              return thin(d);
            }).first;
  }
  thin(d_low);
  reporter.throw_if_cancelled();
  std::sort(keep.begin(), keep.end());
  SimplifyResult result;
  result.input_points = n;
  result.feature_points = kept_high;
  result.length_used = d_low;
  result.source_index.assign(keep.begin(), keep.end());
  result.cloud = cloud.select(result.source_index);
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
