// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "clean/detail/clean_common.h"
#include "core/detail/local_pca.h"
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

// Residuals beyond this many robust standard deviations of the first plane leave the refit
// (an outlier among the neighbours, the far side of a thin part).
constexpr double kRefitSigmas = 2.5;

// The noise scale is the RMS of the plane distances pooled from the neighbours' neighbourhoods
// that lie within this many robust standard deviations (their median's) of zero.
constexpr double kPoolTrim = 3.5;

constexpr int kScaleSmoothing = 3;

// Per-thread buffers of the plane fits (no allocation per point).
struct PlaneScratch {
  std::vector<Vector3d> offsets, kept;
  std::vector<double> residuals;
};

// Distance from the origin to the least-squares plane of `s.offsets` (a neighbourhood seen from
// the point it judges), refitted once without the offsets farther than kRefitSigmas robust
// standard deviations from the first plane. 0 when the offsets span no plane.
double distance_to_local_plane(PlaneScratch& s) {
  const std::vector<Vector3d>& q = s.offsets;
  const detail::LocalPca first = detail::local_pca([&](std::size_t j) { return q[j]; }, q.size());
  if (!first.valid) return 0.0;
  const Vector3d normal = first.normal();
  s.residuals.resize(q.size());
  for (std::size_t j = 0; j < q.size(); ++j) s.residuals[j] = std::abs(normal.dot(q[j] - first.mean));
  const double band = kRefitSigmas * kMadToSigma * median_of(s.residuals);
  s.kept.clear();
  for (const Vector3d& x : q)
    if (std::abs(normal.dot(x - first.mean)) <= band) s.kept.push_back(x);
  if (s.kept.size() == q.size()) return std::abs(normal.dot(first.mean));
  const detail::LocalPca refit = detail::local_pca([&](std::size_t j) { return s.kept[j]; }, s.kept.size());
  return refit.valid ? std::abs(refit.normal().dot(refit.mean)) : std::abs(normal.dot(first.mean));
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
    t.number("surface_sigmas", &P::surface_sigmas,
             "Also drop points farther than this many local noise scales from their neighbours' plane (0: off)")
        .non_negative();
    t.number("surface_floor", &P::surface_floor, "The noise scale is at least this many times the neighbourhood's mean neighbour distance")
        .positive();
    return t;
  }();
  return table;
}

void LocalOutlierParams::validate() const { fields().validate(*this, "remove_local_outliers"); }

namespace {

// One round of remove_local_outliers over `positions` (`t` built over them), advancing
// `reporter` by 2 units a point.
OutlierResult judge_local_outliers(std::span<const Vector3d> positions, const KdTree& t, const LocalOutlierParams& params,
                                   detail::ProgressReporter& reporter) {
  const std::size_t k = static_cast<std::size_t>(params.k);
  const std::size_t n = positions.size();

  // 1. Mean distance to the k nearest others, and who they are.
  std::vector<double> mean_distance(n);
  std::vector<std::uint32_t> neighbour_of(n * k);
  detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.knn(positions[i], k + 1, neighbors);
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
  std::vector<double> ratio(n), reference(n);
  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  // Median over the neighbours of values[j], one per point, into out[i].
  auto neighbour_median = [&](const std::vector<double>& values, std::vector<double>& out) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<double>& local = scratch.local();
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        local.resize(k);
        for (std::size_t u = 0; u < k; ++u) local[u] = values[neighbour_of[i * k + u]];
        out[i] = median_of(local);
      }
    });
    reporter.throw_if_cancelled();
  };
  neighbour_median(mean_distance, reference);
  for (std::size_t i = 0; i < n; ++i)
    ratio[i] = reference[i] > 0.0 ? mean_distance[i] / reference[i] : (mean_distance[i] > 0.0 ? std::numeric_limits<double>::infinity() : 1.0);
  reporter.advance(n / 2);

  // 3. Distance to the plane of the neighbours, in units of the local noise: the noise scale is
  // 1.4826 x the median of the neighbours' own plane distances, pooled once more as the median
  // of those scales over the neighbours (one median of k values varies by about 30 %).
  std::vector<double> plane_distance, noise_scale;
  if (params.surface_sigmas > 0.0) {
    plane_distance.resize(n);
    tbb::enumerable_thread_specific<PlaneScratch> planes;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      PlaneScratch& s = planes.local();
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        s.offsets.resize(k);
        for (std::size_t u = 0; u < k; ++u) s.offsets[u] = positions[neighbour_of[i * k + u]] - positions[i];
        plane_distance[i] = distance_to_local_plane(s);
      }
    });
    reporter.throw_if_cancelled();
    noise_scale.resize(n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<double>& pool = scratch.local();
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        pool.clear();
        for (std::size_t u = 0; u <= k; ++u) {
          const std::size_t j = u == k ? i : neighbour_of[i * k + u];
          for (std::size_t v = 0; v < k; ++v) pool.push_back(plane_distance[neighbour_of[j * k + v]]);
        }
        const double cut = kPoolTrim * kMadToSigma * median_of(pool);
        double sum = 0.0;
        std::size_t count = 0;
        for (double d : pool)
          if (d <= cut) sum += d * d, ++count;
        noise_scale[i] = count > 0 ? sum / double(count) : 0.0;  // a variance until smoothed
      }
    });
    reporter.throw_if_cancelled();
    // Smoothed over the neighbourhoods (the variance's mean over the point and its neighbours,
    // kScaleSmoothing times): one pool still varies by about 15 %.
    std::vector<double> smoothed(n);
    for (int pass = 0; pass < kScaleSmoothing; ++pass) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          double sum = noise_scale[i];
          for (std::size_t u = 0; u < k; ++u) sum += noise_scale[neighbour_of[i * k + u]];
          smoothed[i] = sum / double(k + 1);
        }
      });
      noise_scale.swap(smoothed);
    }
    for (std::size_t i = 0; i < n; ++i) noise_scale[i] = std::max(std::sqrt(noise_scale[i]), params.surface_floor * reference[i]);
  }
  reporter.advance(n - n / 2);
  if (const char* dbg = std::getenv("PS_DEBUG_LOCAL"); dbg && !noise_scale.empty()) {  // DEBUG-REMOVE
    static int round_no = 0;
    FILE* f = std::fopen(fmt::format("{}.{}", dbg, round_no++).c_str(), "w");
    for (std::size_t i = 0; i < n; ++i) std::fprintf(f, "%.17g %.17g %.17g %.9g %.9g %.9g\n", positions[i].x(), positions[i].y(), positions[i].z(), plane_distance[i], noise_scale[i], ratio[i]);
    std::fclose(f);
  }
  std::vector<std::uint32_t>().swap(neighbour_of);

  // 4. Robust cut over all ratios.
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
  for (std::size_t i = 0; i < n; ++i) {
    const bool off_surface = !noise_scale.empty() && plane_distance[i] > params.surface_sigmas * noise_scale[i];
    if (!(ratio[i] > threshold) && !(mean_distance[i] > far) && !off_surface) result.kept.push_back(static_cast<std::uint32_t>(i));
  }
  result.removed = n - result.kept.size();
  return result;
}

}  // namespace

OutlierResult remove_local_outliers(const PointCloud& cloud, const LocalOutlierParams& params, const KdTree* tree,
                                    const ProgressCallback& progress) {
  params.validate();
  detail::check_cloud("remove_local_outliers", cloud, std::size_t(params.k) + 1, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const std::size_t n = cloud.size();
  const bool surface = params.surface_sigmas > 0.0;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, (surface ? 4 : 2) * n);
  OutlierResult result = judge_local_outliers(cloud.positions, t, params, reporter);
  // With the surface test, once more over the points kept: an outlier whose neighbours were
  // partly other outliers (one plane through both, a wide noise scale) now has surface points
  // around it.
  if (surface && result.removed > 0 && result.kept.size() > std::size_t(params.k)) {
    std::vector<Vector3d> kept_positions(result.kept.size());
    for (std::size_t j = 0; j < result.kept.size(); ++j) kept_positions[j] = cloud.positions[result.kept[j]];
    const KdTree kept_tree(kept_positions);
    const OutlierResult second = judge_local_outliers(kept_positions, kept_tree, params, reporter);
    for (std::size_t j = 0; j < second.kept.size(); ++j) result.kept[j] = result.kept[second.kept[j]];
    result.kept.resize(second.kept.size());
    result.removed = n - result.kept.size();
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
