// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Cholesky>
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

// A point's noise variance is the mean of the fits' residual variances of it and its neighbours
// that lie within this squared times their median (a fit across a crease or two sheets)...
constexpr double kPoolTrim = 2.0;
// ... averaged over the point and its neighbours this many times (one neighbourhood's estimate
// varies by about 30 %, which would remove the tail of the noise).
constexpr int kScaleSmoothing = 3;
// The surface test applies where the neighbourhoods' flatness (smallest over middle eigenvalue of
// the surface fits' planes, smoothed as the noise) is at most this: a surface resolved by the
// fit's neighbours (about 0.1-0.2 with noise of half a spacing). Above it (noise wider than the
// neighbourhoods, as on CGAL's sphere_20k.xyz) the fits say nothing about the surface.
constexpr double kMaxFlatness = 0.35;
// An off-surface point with more off-surface neighbours than this, at about the surface's
// density, belongs to a structure (vegetation, a wall of an aerial scan) and is kept.
constexpr std::size_t kMaxOffNeighbours = 1;

// The surface fits use this many times k nearest neighbours: 16 points are too few for a
// quadric's six coefficients to be trimmed reliably, and with noise of half a spacing the 16
// nearest neighbours of a point near an outlier are biased towards it (3D distance favours
// samples displaced its way), so a small fit bends to it and outliers at 5 sigma pass.
constexpr std::size_t kSurfaceFitFactor = 2;

// Per-thread buffers of the surface fits (no allocation per point).
struct FitScratch {
  std::vector<Vector3d> offsets, kept;
  std::vector<double> residuals, leverage, deleted;
};

// A neighbourhood's surface: a quadric height over a plane frame, h = q(u, v) (u, v scaled by
// the neighbourhood's extent), or the plane itself (all coefficients zero).
struct LocalSurface {
  Vector3d normal = Vector3d::Zero(), centre = Vector3d::Zero();
  Vector3d t1 = Vector3d::Zero(), t2 = Vector3d::Zero();  // tangent axes of the plane
  double flatness = 1.0;  // of the plane fit: smallest over middle eigenvalue
  double inv_scale = 0.0;
  std::array<double, 6> c{};  // q = c0 + c1 u + c2 v + c3 u^2 + c4 uv + c5 v^2
  double variance = 0.0;      // residual variance of the fit (degrees of freedom and trim corrected)
  // Distance of `x` (same frame as centre) to the surface: the height above the quadric over
  // the slope's length (first order in the distance).
  double distance(const Vector3d& x) const {
    const Vector3d d = x - centre;
    const double u = inv_scale * t1.dot(d), v = inv_scale * t2.dot(d), h = normal.dot(d);
    const double q = c[0] + c[1] * u + c[2] * v + c[3] * u * u + c[4] * u * v + c[5] * v * v;
    const double qu = inv_scale * (c[1] + 2.0 * c[3] * u + c[4] * v), qv = inv_scale * (c[2] + c[4] * u + 2.0 * c[5] * v);
    return std::abs(h - q) / std::sqrt(1.0 + qu * qu + qv * qv);
  }
};

// Progress units a point of the surface fits (the neighbour search counts 1): they take about
// three times as long as the search of the 2k nearest.
constexpr std::size_t kFitUnits = 3;

// Fewer offsets than this (after trimming) keep the plane: six coefficients need a margin.
constexpr std::size_t kMinQuadricPoints = 10;
// A normal variable trimmed at +-kRefitSigmas (2.5) standard deviations keeps this share of its
// variance: the trimmed fits' residual variance is divided by it.
constexpr double kTrimmedVariance = 0.911;

// Residual variance of `f` over `pts`, `parameters` coefficients fitted, trimmed or not.
double residual_variance(const LocalSurface& f, const std::vector<Vector3d>& pts, double parameters, bool trimmed) {
  if (double(pts.size()) <= parameters) return 0.0;
  double sum = 0.0;
  for (const Vector3d& x : pts) sum += f.distance(x) * f.distance(x);
  return sum / (double(pts.size()) - parameters) / (trimmed ? kTrimmedVariance : 1.0);
}

// The quadric's coefficients over `pts` in the frame of `f` (least squares, normal equations
// in scaled coordinates) and each point's leverage; false when they are ill-posed (points near
// a line).
bool fit_quadric(const std::vector<Vector3d>& pts, LocalSurface& f, std::vector<double>& leverage) {
  Eigen::Matrix<double, 6, 6> ata = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> atb = Eigen::Matrix<double, 6, 1>::Zero();
  auto row_of = [&](const Vector3d& x) {
    const Vector3d d = x - f.centre;
    const double u = f.inv_scale * f.t1.dot(d), v = f.inv_scale * f.t2.dot(d);
    return Eigen::Matrix<double, 6, 1>(1.0, u, v, u * u, u * v, v * v);
  };
  for (const Vector3d& x : pts) {
    const Eigen::Matrix<double, 6, 1> row = row_of(x);
    ata.noalias() += row * row.transpose();
    atb.noalias() += f.normal.dot(x - f.centre) * row;
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(ata);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > 1e-9)) return false;
  const Eigen::Matrix<double, 6, 1> x = ldlt.solve(atb);
  if (!x.allFinite()) return false;
  for (int i = 0; i < 6; ++i) f.c[std::size_t(i)] = x[i];
  leverage.clear();
  for (const Vector3d& p : pts) {
    const Eigen::Matrix<double, 6, 1> row = row_of(p);
    leverage.push_back(row.dot(ldlt.solve(row)));
  }
  return true;
}

// The surface of `s.offsets` (a neighbourhood seen from the point it judges, the point
// excluded): the least-squares plane, refitted once without the offsets farther than
// kRefitSigmas robust standard deviations from the first plane; then a quadric height over it,
// fitted to all offsets and refitted once without those whose deleted residual (residual over
// 1 - leverage: the quadric bends to a point at its rim, which hides an outlier there) is beyond
// kRefitSigmas robust standard deviations. A plane bends away from thin, strongly curved parts
// (a statue's limbs, horns): the quadric follows them, so its residuals measure the noise, not
// the curvature. The plane when the quadric is ill-posed; a zero normal and flatness 1 when the
// offsets span no plane.
LocalSurface fit_local_surface(FitScratch& s) {
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
  detail::LocalPca plane = first;
  if (s.kept.size() != q.size()) {
    const detail::LocalPca refit = detail::local_pca([&](std::size_t j) { return s.kept[j]; }, s.kept.size());
    if (refit.valid) plane = refit;
  }
  LocalSurface f;
  f.normal = plane.normal();
  f.centre = plane.mean;
  f.flatness = plane.eigenvalues[0] / plane.eigenvalues[1];
  f.t1 = plane.eigenvectors.col(2).normalized();
  f.t2 = f.normal.cross(f.t1);
  f.variance = residual_variance(f, s.kept, 3.0, s.kept.size() != q.size());
  const double extent = std::sqrt(std::max(plane.eigenvalues[2], 0.0));
  if (!(extent > 0.0) || q.size() < kMinQuadricPoints) return f;
  f.inv_scale = 1.0 / extent;
  LocalSurface quadric = f;
  if (!fit_quadric(q, quadric, s.leverage)) return f;
  s.deleted.resize(q.size());
  for (std::size_t j = 0; j < q.size(); ++j) s.deleted[j] = quadric.distance(q[j]) / std::max(1.0 - s.leverage[j], 0.05);
  s.residuals = s.deleted;
  const double quadric_band = kRefitSigmas * kMadToSigma * median_of(s.residuals);
  s.kept.clear();
  for (std::size_t j = 0; j < q.size(); ++j)
    if (s.deleted[j] <= quadric_band) s.kept.push_back(q[j]);
  const bool trimmed = s.kept.size() != q.size();
  if (trimmed && (s.kept.size() < kMinQuadricPoints || !fit_quadric(s.kept, quadric, s.leverage))) return f;
  quadric.variance = residual_variance(quadric, s.kept, 6.0, trimmed);
  return quadric;
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
             "Also drop points farther than this many local noise scales from their neighbours' surface fits (0: off)")
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
// `reporter` by 2 units a point, 2 + kFitUnits with the surface test.
OutlierResult judge_local_outliers(std::span<const Vector3d> positions, const KdTree& t, const LocalOutlierParams& params,
                                   detail::ProgressReporter& reporter) {
  const std::size_t k = static_cast<std::size_t>(params.k);
  const std::size_t n = positions.size();

  // 1. Mean distance to the k nearest others, and who they are; with the surface test the
  // kSurfaceFitFactor x k nearest (nearest first: the first k are the neighbourhood).
  const std::size_t m = params.surface_sigmas > 0.0 ? kSurfaceFitFactor * k : k;
  std::vector<double> mean_distance(n);
  std::vector<std::uint32_t> neighbour_of(n * m);
  detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.knn(positions[i], m + 1, neighbors);
    // The point itself is normally first, but among duplicates another may precede it: skip it
    // wherever it is and keep k others (there are k + 1 points at least; fewer than m + 1 leave
    // the point itself in the remaining slots).
    std::size_t used = 0;
    double sum = 0.0;
    for (const Neighbor& nb : neighbors) {
      if (nb.index == i || used == m) continue;
      neighbour_of[std::size_t(i) * m + used] = nb.index;
      if (used++ < k) sum += std::sqrt(nb.squared_distance);
    }
    for (std::size_t u = used; u < m; ++u) neighbour_of[std::size_t(i) * m + u] = i;
    mean_distance[i] = sum / double(std::clamp<std::size_t>(used, 1, k));
  });

  // 2. Ratio to the neighbourhood's median mean distance. The passes below run in parallel in
  // the tree's spatial order (neighbours close in memory).
  const std::span<const std::uint32_t> order = t.spatial_order();
  // `units` progress units a point, reported block by block (0: none).
  auto for_points = [&](auto&& body, std::size_t units = 0) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) body(std::size_t(order[pos]));
      if (units > 0) reporter.advance(units * r.size());
    });
    reporter.throw_if_cancelled();
  };
  auto neighbours = [&](std::size_t i) { return std::span<const std::uint32_t>(neighbour_of.data() + i * m, k); };
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

  // 3. Distance to the surface in units of the local noise. Each point's surface (a quadric,
  // fit_local_surface) is fitted to its kSurfaceFitFactor x k nearest neighbours (itself
  // excluded); the residual variances of the point's and its neighbours' fits, the mean of
  // those within kPoolTrim^2 x their median (a fit spanning a crease or two sheets), smoothed
  // (the mean over the point and its neighbours, kScaleSmoothing times: one neighbourhood's
  // estimate varies by about 30 %), give the noise, at least surface_floor x the neighbours'
  // mean distance. The point's distance to the surface is the median of its distances to its
  // neighbours' surfaces (between two sheets its own fit runs between them; theirs are the
  // sheets).
  std::vector<double> noise_scale, surface_distance;
  std::vector<std::uint8_t> off_surface;  // empty without the surface test
  if (params.surface_sigmas > 0.0) {
    std::vector<LocalSurface> fit(n);
    tbb::enumerable_thread_specific<FitScratch> fits;
    for_points([&](std::size_t i) {
      FitScratch& s = fits.local();
      s.offsets.clear();
      for (std::uint32_t j : std::span<const std::uint32_t>(neighbour_of.data() + i * m, m))
        if (j != i) s.offsets.push_back(positions[j] - positions[i]);
      fit[i] = fit_local_surface(s);
      fit[i].centre += positions[i];
    }, kFitUnits);
    noise_scale.resize(n);
    for_points([&](std::size_t i) {
      std::vector<double>& pool = scratch.local();
      pool.assign(1, fit[i].variance);
      for (std::uint32_t j : neighbours(i)) pool.push_back(fit[j].variance);
      const double cut = kPoolTrim * kPoolTrim * median_of(pool);
      double sum = 0.0;
      std::size_t count = 0;
      for (double v : pool)
        if (v <= cut) sum += v, ++count;
      noise_scale[i] = count > 0 ? sum / double(count) : 0.0;  // a variance until smoothed
    });
    std::vector<double> flatness(n), smoothed(n);
    for (std::size_t i = 0; i < n; ++i) flatness[i] = fit[i].flatness;
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
      for (std::uint32_t j : neighbours(i)) local.push_back(fit[j].distance(positions[i]));
      surface_distance[i] = median_of(local);
    });
    // Off the surface: far from the neighbours' surfaces where the neighbourhoods are surfaces;
    // a sparse point also when its own neighbours form no surface (outliers inside a closed
    // part, each other's neighbours). Kept anyway: a point at about the surface's density with
    // more than kMaxOffNeighbours off-surface neighbours (a structure).
    std::vector<double> sorted_distance = mean_distance;
    const double dense = params.min_ratio * median_of(sorted_distance);
    std::vector<std::uint8_t> off(n);
    for (std::size_t i = 0; i < n; ++i) {
      const bool sparse = mean_distance[i] > dense;
      const bool far_from_surfaces = surface_distance[i] > params.surface_sigmas * noise_scale[i];
      off[i] = sparse ? far_from_surfaces || fit[i].flatness > kMaxFlatness : flatness[i] <= kMaxFlatness && far_from_surfaces;
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
  // Units a point and round: the neighbours 1, the ratios 1/2, the surface fits kFitUnits, the
  // rest 1/2; with the surface test a second round over the points kept.
  detail::ProgressReporter reporter(progress, 0.0, 1.0, (surface ? 2 * (2 + kFitUnits) : 2) * n);
  OutlierResult result = judge_local_outliers(cloud.positions, t, params, reporter);
  // With the surface test, once more over the points kept: an outlier whose neighbours were
  // partly other outliers (one fit through both, a wide noise scale) now has surface points
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
