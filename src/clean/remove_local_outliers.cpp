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

// A point's noise variance is the mean square of the plane distances of it and its neighbours
// that lie within this many robust standard deviations (from their median) of zero...
constexpr double kPoolTrim = 3.5;
// ... averaged over the point and its neighbours this many times (one neighbourhood's estimate
// varies by about 30 %, which would remove the tail of the noise).
constexpr int kScaleSmoothing = 3;
// The surface test applies where the neighbourhoods' flatness (smallest over middle eigenvalue of
// the plane fits, smoothed as the noise) is at most this: a surface resolved by k neighbours
// (about 0.1-0.2 with noise of half a spacing). Above it (noise wider than the neighbourhoods,
// as on CGAL's sphere_20k.xyz, about 0.5) the planes say nothing about the surface.
constexpr double kMaxFlatness = 0.35;
// An off-surface point with more off-surface neighbours than this, at about the surface's
// density, belongs to a structure (vegetation, a wall of an aerial scan) and is kept.
constexpr std::size_t kMaxOffNeighbours = 1;

// Per-thread buffers of the plane fits (no allocation per point).
struct PlaneScratch {
  std::vector<Vector3d> offsets, kept;
  std::vector<double> residuals;
};

// The least-squares plane of `s.offsets` (a neighbourhood seen from the point it judges, the
// point excluded), refitted once without the offsets farther than kRefitSigmas robust standard
// deviations from the first plane: its unit normal, a point on it (offsets' frame) and its
// flatness (smallest over middle eigenvalue). A zero normal and flatness 1 when the offsets span
// no plane.
struct LocalPlane {
  Vector3d normal = Vector3d::Zero(), centre = Vector3d::Zero();
  double flatness = 1.0;
};
LocalPlane fit_local_plane(PlaneScratch& s) {
  const std::vector<Vector3d>& q = s.offsets;
  const detail::LocalPca first = detail::local_pca([&](std::size_t j) { return q[j]; }, q.size());
  if (!first.valid) return {};
  const Vector3d normal = first.normal();
  s.residuals.resize(q.size());
  for (std::size_t j = 0; j < q.size(); ++j) s.residuals[j] = std::abs(normal.dot(q[j] - first.mean));
  const double band = kRefitSigmas * kMadToSigma * median_of(s.residuals);
  s.kept.clear();
  for (const Vector3d& x : q)
    if (std::abs(normal.dot(x - first.mean)) <= band) s.kept.push_back(x);
  if (s.kept.size() == q.size()) return {normal, first.mean, first.eigenvalues[0] / first.eigenvalues[1]};
  const detail::LocalPca refit = detail::local_pca([&](std::size_t j) { return s.kept[j]; }, s.kept.size());
  return refit.valid ? LocalPlane{refit.normal(), refit.mean, refit.eigenvalues[0] / refit.eigenvalues[1]} : LocalPlane{normal, first.mean, 1.0};
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

  // 2. Ratio to the neighbourhood's median mean distance. The passes below run in parallel in
  // the tree's spatial order (neighbours close in memory).
  const std::span<const std::uint32_t> order = t.spatial_order();
  auto for_points = [&](auto&& body) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) body(std::size_t(order[pos]));
    });
    reporter.throw_if_cancelled();
  };
  auto neighbours = [&](std::size_t i) { return std::span<const std::uint32_t>(neighbour_of.data() + i * k, k); };
  std::vector<double> ratio(n), reference(n);
  tbb::enumerable_thread_specific<std::vector<double>> scratch;
  for_points([&](std::size_t i) {
    std::vector<double>& local = scratch.local();
    local.clear();
    for (std::uint32_t j : neighbours(i)) local.push_back(mean_distance[j]);
    reference[i] = median_of(local);
    ratio[i] = reference[i] > 0.0 ? mean_distance[i] / reference[i] : (mean_distance[i] > 0.0 ? std::numeric_limits<double>::infinity() : 1.0);
  });
  reporter.advance(n / 2);

  // 3. Distance to the surface in units of the local noise. Each point's plane is fitted to its
  // neighbours (itself excluded); its distance to that plane, over the point and its neighbours,
  // gives the noise: the RMS of those within kPoolTrim robust standard deviations, smoothed
  // (the variance's mean over the point and its neighbours, kScaleSmoothing times: one
  // neighbourhood's estimate varies by about 30 %), at least surface_floor x the neighbours'
  // mean distance. The point's distance to the surface is the median of its distances to its
  // neighbours' planes (between two sheets its own plane runs between them; theirs are the
  // sheets).
  std::vector<double> noise_scale, surface_distance;
  std::vector<std::uint8_t> off_surface;  // empty without the surface test
  if (params.surface_sigmas > 0.0) {
    std::vector<double> plane_distance(n);
    std::vector<LocalPlane> plane(n);
    tbb::enumerable_thread_specific<PlaneScratch> planes;
    for_points([&](std::size_t i) {
      PlaneScratch& s = planes.local();
      s.offsets.clear();
      for (std::uint32_t j : neighbours(i)) s.offsets.push_back(positions[j] - positions[i]);
      plane[i] = fit_local_plane(s);
      plane_distance[i] = std::abs(plane[i].normal.dot(plane[i].centre));
      plane[i].centre += positions[i];
    });
    noise_scale.resize(n);
    for_points([&](std::size_t i) {
      std::vector<double>& pool = scratch.local();
      pool.assign(1, plane_distance[i]);
      for (std::uint32_t j : neighbours(i)) pool.push_back(plane_distance[j]);
      const double cut = kPoolTrim * kMadToSigma * median_of(pool);
      double sum = 0.0;
      std::size_t count = 0;
      for (std::uint32_t j : neighbours(i))
        if (plane_distance[j] <= cut) sum += plane_distance[j] * plane_distance[j], ++count;
      if (plane_distance[i] <= cut) sum += plane_distance[i] * plane_distance[i], ++count;
      noise_scale[i] = count > 0 ? sum / double(count) : 0.0;  // a variance until smoothed
    });
    std::vector<double> flatness(n), smoothed(n);
    for (std::size_t i = 0; i < n; ++i) flatness[i] = plane[i].flatness;
    auto smooth = [&](std::vector<double>& values) {
      for (int pass = 0; pass < kScaleSmoothing; ++pass) {
        for_points([&](std::size_t i) {
          double sum = values[i];
          for (std::uint32_t j : neighbours(i)) sum += values[j];
          smoothed[i] = sum / double(k + 1);
        });
        values.swap(smoothed);
      }
    };
    smooth(noise_scale);
    smooth(flatness);
    surface_distance.resize(n);
    for_points([&](std::size_t i) {
      noise_scale[i] = std::max(std::sqrt(noise_scale[i]), params.surface_floor * reference[i]);
      std::vector<double>& local = scratch.local();
      local.clear();
      for (std::uint32_t j : neighbours(i)) local.push_back(std::abs(plane[j].normal.dot(positions[i] - plane[j].centre)));
      surface_distance[i] = median_of(local);
    });
    // Off the surface: far from the neighbours' planes where the neighbourhoods are surfaces;
    // a sparse point also when its own neighbours form no surface (outliers inside a closed
    // part, each other's neighbours). Kept anyway: a point at about the surface's density with
    // more than kMaxOffNeighbours off-surface neighbours (a structure).
    std::vector<double> sorted_distance = mean_distance;
    const double dense = params.min_ratio * median_of(sorted_distance);
    std::vector<std::uint8_t> off(n);
    for (std::size_t i = 0; i < n; ++i) {
      const bool sparse = mean_distance[i] > dense;
      const bool far_from_planes = surface_distance[i] > params.surface_sigmas * noise_scale[i];
      off[i] = sparse ? far_from_planes || plane[i].flatness > kMaxFlatness : flatness[i] <= kMaxFlatness && far_from_planes;
    }
    off_surface.assign(n, 0);
    for_points([&](std::size_t i) {
      if (!off[i]) return;
      std::size_t others = 0;
      for (std::uint32_t j : neighbours(i)) others += off[j];
      off_surface[i] = others <= kMaxOffNeighbours || mean_distance[i] > dense;
    });
  }
  reporter.advance(n - n / 2);
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
    if (!(ratio[i] > threshold) && !(mean_distance[i] > far) && !(!off_surface.empty() && off_surface[i]))
      result.kept.push_back(static_cast<std::uint32_t>(i));
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
