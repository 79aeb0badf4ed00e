// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/remove_outliers.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "clean/detail/clean_common.h"
#include "core/detail/plane_fit.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/shape/primitives.h"
#include "pointsurf/spatial/voxel_grid.h"

namespace pointsurf {
namespace {

constexpr std::size_t kGrain = 256;
// RANSAC: the smallest sine of the angle at the first sample between the other two.
constexpr double kMinSine = 0.1;
// RANSAC: planes passing within kGate * distance of the point are refitted and tested.
constexpr double kGate = 2.0;
// RANSAC: a point within this many RMS residuals of a refitted plane's inliers lies on it.
constexpr double kNoiseSigmas = 4.0;
// RANSAC: the foot of a kept point lies within this many in-plane standard deviations of the
// centroid of the plane's inliers (1.6 at a cube corner, 0.7 on an open border).
constexpr double kSpread = 2.5;
// RANSAC: a plane through the point other than the dominant one needs this share of
// min_support among points off the dominant plane (4 of 23 neighbours by default: a cube
// corner's other faces reach it, a cluster of a few drift points mostly does not).
constexpr double kOwnShare = 0.5;

OutlierResult collect(const std::vector<std::uint8_t>& keep, double threshold) {
  OutlierResult result;
  result.threshold = threshold;
  result.kept.reserve(keep.size());
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i] != 0) result.kept.push_back(static_cast<std::uint32_t>(i));
  result.removed = keep.size() - result.kept.size();
  return result;
}

using detail::mix;
using detail::Plane;
using detail::seed_for;
using Fit = detail::PlaneFit;

Fit fit_of(std::span<const Eigen::Vector3d> q, const Plane& plane, double distance) { return detail::msac_fit(q, plane, distance); }

// The least-squares plane of the inliers, whose foot test uses the in-plane spread kSpread.
std::optional<Plane> refit(std::span<const Eigen::Vector3d> q, const Plane& plane, double distance) {
  return detail::refit_plane(q, plane, distance, kMinSine, kSpread);
}

// Whether a refitted plane passes close enough to the point (the origin): within `distance`,
// or within kNoiseSigmas RMS residuals of its inliers up to kGate * distance, with the point's
// foot inside the inliers' spread.
bool passes_near(const Plane& fitted, double distance) {
  return fitted.surrounds && std::abs(fitted.offset) <= std::clamp(kNoiseSigmas * fitted.rms, distance, kGate * distance);
}

// Decides one point from the offsets `q` of its neighbours (itself excluded); see the header
// for the tests. `candidates` is scratch space (reused, so nothing is allocated per point
// once it has grown to `iterations`).
bool fits_local_plane(std::span<const Eigen::Vector3d> q, double distance, const RansacOutlierParams& params, std::uint64_t state,
                      std::vector<Plane>& candidates) {
  const std::size_t m = q.size();
  if (m < 3) return false;
  const std::size_t needed = static_cast<std::size_t>(std::ceil(params.min_support * double(m) - 1e-9));
  const std::size_t enough = std::max(needed, static_cast<std::size_t>(std::ceil(params.min_relative_support * double(m) - 1e-9)));
  const std::size_t own_needed = static_cast<std::size_t>(std::ceil(kOwnShare * params.min_support * double(m) - 1e-9));
  candidates.clear();
  Plane dominant;  // the best-scoring plane of the neighbourhood
  Fit dominant_fit;
  bool dominant_refitted = false;
  for (int it = 0; it < params.iterations; ++it) {
    // Three distinct neighbours, uniformly.
    const std::size_t a = (state = mix(state)) % m;
    std::size_t b = (state = mix(state)) % (m - 1);
    b += b >= a;
    std::size_t c = (state = mix(state)) % (m - 2);
    c += c >= std::min(a, b);
    c += c >= std::max(a, b);
    const Eigen::Vector3d u = q[b] - q[a], v = q[c] - q[a];
    Eigen::Vector3d normal = u.cross(v);
    const double length = normal.norm();
    // Nearly collinear samples (angle below about 6 degrees) give no reliable plane.
    if (!(length > kMinSine * u.norm() * v.norm())) continue;
    normal /= length;
    const Plane plane{normal, -normal.dot(q[a])};
    const Fit fit = fit_of(q, plane, distance);
    if (fit.score > dominant_fit.score) dominant = plane, dominant_fit = fit, dominant_refitted = false;
    if (std::abs(plane.offset) > kGate * distance || fit.support < needed) continue;
    const std::optional<Plane> fitted = refit(q, plane, distance);
    if (!fitted || !passes_near(*fitted, distance)) continue;
    const Fit refit_fit = fit_of(q, *fitted, distance);
    if (refit_fit.support < needed) continue;
    // A plane through the point holding this share of all neighbours dominates any other.
    if (refit_fit.support >= enough) return true;
    candidates.push_back(*fitted);
    candidates.back().score = refit_fit.score;
    if (refit_fit.score > dominant_fit.score) dominant = *fitted, dominant_fit = refit_fit, dominant_refitted = true;
  }
  if (candidates.empty()) return false;
  if (!dominant_refitted)
    if (const std::optional<Plane> fitted = refit(q, dominant, distance)) {
      const Fit fit = fit_of(q, *fitted, distance);
      if (fit.score >= dominant_fit.score) dominant = *fitted, dominant_fit = fit, dominant_refitted = true;
    }
  // On the dominant plane itself.
  if (dominant_refitted ? passes_near(dominant, distance) : std::abs(dominant.offset) <= distance) return true;
  // Otherwise a plane through the point must score min_relative_support of the dominant plane
  // and hold kOwnShare * min_support of the neighbours on its own (not within `distance` of
  // the dominant plane): a steep plane through a strip of the surface below a drift point, or
  // through a few other drift points and that strip, does not; a crease's other face does.
  for (const Plane& plane : candidates) {
    if (plane.score < params.min_relative_support * dominant_fit.score) continue;
    std::size_t own = 0;
    for (const Eigen::Vector3d& x : q)
      own += std::abs(plane.normal.dot(x) + plane.offset) <= distance && std::abs(dominant.normal.dot(x) + dominant.offset) > distance;
    if (own >= own_needed) return true;
  }
  return false;
}

}  // namespace

const FieldTable<StatisticalOutlierParams>& StatisticalOutlierParams::fields() {
  static const FieldTable<StatisticalOutlierParams> table = [] {
    using P = StatisticalOutlierParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point, the point included").at_least(1).unit("points");
    t.number("std_ratio", &P::std_ratio, "Drop points whose mean kNN distance >= mean + std_ratio x std").positive();
    return t;
  }();
  return table;
}

void StatisticalOutlierParams::validate() const { fields().validate(*this, "remove_statistical_outliers"); }

const FieldTable<RadiusOutlierParams>& RadiusOutlierParams::fields() {
  static const FieldTable<RadiusOutlierParams> table = [] {
    using P = RadiusOutlierParams;
    FieldTable<P> t;
    t.integer("min_neighbors", &P::min_neighbours, "Keep points with at least this many others within the radius").at_least(1).unit("points").was("min_neighbours");
    t.length("radius", &P::radius, "Search radius").positive().was("radius_in_spacings");
    return t;
  }();
  return table;
}

void RadiusOutlierParams::validate() const { fields().validate(*this, "remove_radius_outliers"); }

const FieldTable<RansacOutlierParams>& RansacOutlierParams::fields() {
  static const FieldTable<RansacOutlierParams> table = [] {
    using P = RansacOutlierParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbourhood size, the point included").at_least(4).unit("points");
    t.length("distance", &P::distance, "Plane distance").positive().was("distance_in_spacings");
    t.integer("iterations", &P::iterations, "Random planes tried per point").at_least(1);
    t.number("min_support", &P::min_support, "Fraction of the neighbourhood a plane needs").range(0.0, 1.0, true, false);
    t.number("min_relative_support", &P::min_relative_support,
             "A plane through the point holding (or scoring) this fraction of the neighbours (of the dominant plane) keeps it")
        .range(0.0, 1.0);
    t.integer("seed", &P::seed, "Random seed");
    t.boolean("primitives", &P::primitives, "Judge points explained by planes, spheres, cylinders, cones (efficient RANSAC) by those");
    t.number("primitive_band", &P::primitive_band, "A point amid a primitive's inliers farther than this from it is an outlier")
        .unit("plane distances")
        .positive();
    return t;
  }();
  return table;
}

void RansacOutlierParams::validate() const { fields().validate(*this, "remove_ransac_outliers"); }

OutlierResult remove_statistical_outliers(const PointCloud& cloud, const StatisticalOutlierParams& params, const KdTree* tree,
                                          const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_statistical_outliers";
  params.validate();
  detail::check_cloud(fn, cloud, 2, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const std::size_t n = cloud.size(), k = static_cast<std::size_t>(params.k);

  std::vector<double> mean_distance(n);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);
  detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    t.knn(cloud.positions[i], k, neighbors);
    double sum = 0.0;
    for (const Neighbor& nb : neighbors) sum += std::sqrt(nb.squared_distance);
    mean_distance[i] = sum / double(neighbors.size());
  });
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return statistical_outliers_from_distances(mean_distance, params.std_ratio);
}

OutlierResult statistical_outliers_from_distances(std::span<const double> mean_distances, double std_ratio) {
  constexpr std::string_view fn = "statistical_outliers_from_distances";
  detail::check_positive(fn, "std_ratio", std_ratio);
  const std::size_t n = mean_distances.size();
  if (n < 2) throw UsageError(fmt::format("{}: needs at least 2 distances, got {}", fn, n));
  // Serial sums in index order, as Open3D does them, so that a point at the threshold is
  // decided the same way. Zero mean distances count in N but not in the squared deviations.
  double sum = 0.0;
  for (double d : mean_distances) sum += d;
  const double mean = sum / double(n);
  double squares = 0.0;
  for (double d : mean_distances)
    if (d > 0.0) squares += (d - mean) * (d - mean);
  const double threshold = mean + std_ratio * std::sqrt(squares / double(n - 1));
  std::vector<std::uint8_t> keep(n);
  for (std::size_t i = 0; i < n; ++i) keep[i] = mean_distances[i] > 0.0 && mean_distances[i] < threshold;
  return collect(keep, threshold);
}

OutlierResult remove_radius_outliers(const PointCloud& cloud, const RadiusOutlierParams& params, const KdTree* tree,
                                     const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_radius_outliers";
  params.validate();
  detail::check_cloud(fn, cloud, 2, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const double radius = detail::resolve_length(params.radius, t);
  // The point itself is among the results; counting stops once it has min_neighbours others.
  const std::size_t wanted = static_cast<std::size_t>(params.min_neighbours) + 1;

  std::vector<std::uint8_t> keep(cloud.size());
  detail::ProgressReporter reporter(progress, 0.0, 1.0, cloud.size());
  if (radius > 0.0) {
    // A voxel grid with cells of the radius: each cell scans its 27-cell block once for all of
    // its points (own cell first, so dense clouds stop counting early); the same counts as
    // the tree's hybrid query.
    const VoxelGrid grid(cloud.positions, radius, &t);
    const std::vector<std::uint32_t> counts = grid.count_within(radius, static_cast<std::uint32_t>(wanted));
    for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = counts[i] >= wanted;
  } else {
    detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
      t.hybrid(cloud.positions[i], wanted, radius, neighbors);
      keep[i] = neighbors.size() >= wanted;
    });
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return collect(keep, radius);
}

OutlierResult remove_ransac_outliers(const PointCloud& cloud, const RansacOutlierParams& params, const KdTree* tree,
                                     const ProgressCallback& progress) {
  constexpr std::string_view fn = "remove_ransac_outliers";
  params.validate();
  detail::check_cloud(fn, cloud, 4, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const double distance = detail::resolve_length(params.distance, t);
  const std::size_t k = static_cast<std::size_t>(params.k);

  // Primitives first (the detector needs normals: estimated on a copy when there are none).
  PrimitiveResult found;
  if (params.primitives) {
    PrimitiveParams pp;
    if (distance > 0.0) pp.epsilon = Length::cloud(distance);  // 0 (coincident points): the default, 1 spacing, is 0 too
    pp.band_in_epsilons = 1.0;  // a primitive's points are kept: only those within distance
    pp.seed = params.seed;
    if (cloud.has_normals()) {
      found = detect_primitives(cloud, pp);
    } else {
      PointCloud oriented;
      oriented.positions = cloud.positions;
      estimate_normals(oriented, {.keep_variation = false}, &t);
      found = detect_primitives(oriented, pp);
    }
  }
  const std::size_t primitive_count = found.primitives.size();
  const double band = params.primitive_band * distance;

  std::vector<std::uint8_t> keep(cloud.size());
  struct Scratch {
    std::vector<Eigen::Vector3d> offsets;
    std::vector<Plane> candidates;
    std::vector<std::uint32_t> votes;
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, cloud.size());
  detail::for_each_point(t, reporter, [&](std::uint32_t i, std::vector<Neighbor>& neighbors) {
    const Eigen::Vector3d& p = cloud.positions[i];
    if (primitive_count > 0 && found.labels[i] >= 0) {
      keep[i] = 1;
      return;
    }
    t.knn(p, k, neighbors);
    Scratch& local = scratch.local();
    if (primitive_count > 0) {
      // Amid a primitive's inliers (3/4 of the neighbours) but far from every such
      // primitive: an outlier, whatever plane a curved strip below it offers.
      std::vector<std::uint32_t>& votes = local.votes;
      votes.assign(primitive_count, 0);
      for (const Neighbor& nb : neighbors)
        if (nb.index != i && found.labels[nb.index] >= 0) ++votes[static_cast<std::size_t>(found.labels[nb.index])];
      bool owned = false, near = false;
      for (std::size_t l = 0; l < primitive_count; ++l)
        if (4 * votes[l] >= 3 * neighbors.size()) {
          owned = true;
          near = near || found.primitives[l].distance(p) <= band;
        }
      if (owned && !near) {
        keep[i] = 0;
        return;
      }
    }
    // Offsets of the other points from this one: small numbers even for georeferenced clouds.
    // The point itself takes no part in the fits, so it cannot support a plane through itself.
    std::vector<Eigen::Vector3d>& q = local.offsets;
    q.clear();
    for (const Neighbor& nb : neighbors)
      if (nb.index != i) q.push_back(t.point(nb.index) - p);
    keep[i] = fits_local_plane(q, distance, params, seed_for(params.seed, p), local.candidates);
  });
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return collect(keep, distance);
}

const ResultTable<OutlierResult>& OutlierResult::results(const std::string& method) {
  // The threshold of each removal method: its key and doc (local's is a ratio, the others lengths).
  struct ThresholdName {
    const char* method;
    const char* key;
    const char* doc;
  };
  static constexpr ThresholdName kThresholds[] = {
      {"local", "ratio_threshold", "Ratio to the neighbourhood's mean distance above which a point was dropped"},
      {"sor", "mean_distance_threshold", "Mean neighbour distance above which a point was dropped"},
      {"radius", "radius_used", "Search radius used"},
      {"ransac", "distance_used", "Plane distance used"},
  };
  static const std::vector<ResultTable<OutlierResult>> tables = [] {
    std::vector<ResultTable<OutlierResult>> out;
    for (const ThresholdName& n : kThresholds) {
      ResultTable<OutlierResult> t;
      t.count("removed", &OutlierResult::removed, "Points removed as outliers").as_count();
      ResultSpec& spec = t.number(n.key, &OutlierResult::threshold, n.doc);
      if (std::string(n.method) != "local") spec.with_unit("cloud units");
      out.push_back(std::move(t));
    }
    return out;
  }();
  for (std::size_t i = 0; i < std::size(kThresholds); ++i)
    if (method == kThresholds[i].method) return tables[i];
  throw std::logic_error("OutlierResult: no removal method " + method);
}

PointCloud keep_points(const PointCloud& cloud, std::span<const std::uint32_t> kept) {
  std::vector<std::size_t> indices(kept.begin(), kept.end());
  for (std::size_t i : indices)
    if (i >= cloud.size()) throw UsageError(fmt::format("keep_points: index {} out of range for {} points", i, cloud.size()));
  return cloud.select(indices);
}

}  // namespace pointsurf
