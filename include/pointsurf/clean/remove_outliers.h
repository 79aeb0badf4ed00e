// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Outlier removal: statistical (mean kNN distance), radius (too few neighbours within r) and
// local RANSAC planes (too far from the dominant least-squares planes of the neighbourhood).
// Each function only decides which points to keep; keep_points() applies the decision.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

/// Which points an outlier filter keeps.
struct OutlierResult {
  std::vector<std::uint32_t> kept;  // indices of the kept points, ascending (K <= N)
  std::size_t removed = 0;          // N - K: points judged outliers
  double threshold = 0.0;           // the cut actually used, cloud units: statistical: mean kNN
                                    // distance above which a point is dropped; radius: the
                                    // search radius; RANSAC: the plane distance

  /// The reported members (core/results.h) for the removal `method`: local, sor, radius or
  /// ransac (the clean stage's names); the threshold's key says what it is (ratio_threshold,
  /// mean_distance_threshold, radius_used, distance_used). std::logic_error for another name.
  static const ResultTable<OutlierResult>& results(const std::string& method);
};

struct StatisticalOutlierParams {
  int k = 20;              // neighbours per point, the point itself included (Open3D's
                           // nb_neighbors), >= 1
  double std_ratio = 2.0;  // drop a point whose mean distance is >= mean + std_ratio * std, > 0
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<StatisticalOutlierParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Statistical outlier removal (Rusu et al. 2008), defined exactly as Open3D 0.16's
/// PointCloud::remove_statistical_outlier so that both keep the same points:
///   d_i  = mean of the Euclidean distances from p_i to its k nearest points (p_i included,
///          distance 0), over all N points;
///   mean = sum_i d_i / N;  std = sqrt(sum_{i: d_i > 0} (d_i - mean)^2 / (N - 1))  (sample std);
///   p_i is kept iff 0 < d_i < mean + std_ratio * std.
/// Like Open3D, a point whose k nearest points all coincide with it (d_i = 0, a stack of at
/// least k exact duplicates) is dropped: run remove_duplicates first on such data.
/// `tree` (optional) must be built over `cloud.positions`. One parallel pass (oneTBB) in the
/// tree's spatial order, no neighbour lists stored; memory O(N). Thread-safe for distinct
/// calls. Throws UsageError for k < 1, std_ratio <= 0, fewer than 2 points or a tree of
/// another size; CancelledError when `progress` returns false.
OutlierResult remove_statistical_outliers(const PointCloud& cloud, const StatisticalOutlierParams& params = {},
                                          const KdTree* tree = nullptr, const ProgressCallback& progress = {});

/// The statistical cut alone, for mean neighbour distances computed elsewhere (one per point,
/// cloud units): keeps a point when 0 < d_i < mean + std_ratio × std of the d_i, the rule and
/// summation order of remove_statistical_outliers. With estimate_normals'
/// `keep_mean_distance`, normals and outlier removal share one kNN pass (remove the points
/// afterwards: their normals and variation are those of the full cloud). Throws UsageError for
/// std_ratio <= 0 or fewer than 2 distances.
OutlierResult statistical_outliers_from_distances(std::span<const double> mean_distances, double std_ratio);

struct LocalOutlierParams {
  int k = 16;                // neighbours per point, the point itself excluded, >= 2
  double min_ratio = 3.0;    // a point is dropped only when its mean neighbour distance is above
                             // this many times its neighbourhood's (density-relative), > 1; 3
                             // catches points about 10 spacings or more off the surface
  double mad_sigmas = 10.0;  // ... and above the median ratio by this many robust standard
                             // deviations (1.4826 x MAD) of the ratios, > 0
  double far_ratio = 12.0;   // also dropped: a point whose mean neighbour distance is above this
                             // many times the median over the cloud (groups of far outliers that
                             // are each other's neighbours), > 1
  double surface_sigmas = 4.25;  // also dropped: a point farther than this many local noise
                                // scales from the surface (quadric) fitted to its neighbours (see
                                // below), >= 0; 0 turns the surface test off
  double surface_floor = 0.1;   // the noise scale is at least this many times the neighbourhood's
                                // mean neighbour distance (clean, exact surfaces), > 0
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<LocalOutlierParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Density-relative and surface-distance outlier removal, the default of the clean stage: a
/// point is an outlier when it lies far from the surface compared with the spacing around it,
/// so sparse and dense parts of one scan are judged alike (statistical removal, which compares
/// every point with the global mean, removes the sparse parts of a scan of varying density), or
/// far from the surface compared with the local noise.
/// Density test:
///   d_i = mean distance from p_i to its k nearest other points;
///   r_i = d_i / median of d_j over those k neighbours (1 on any evenly sampled surface,
///         whatever its density; large for a point far from the surface its neighbours lie on);
///   p_i is dropped iff r_i > max(min_ratio, median(r) + mad_sigmas * 1.4826 * MAD(r)), or
///   d_i > far_ratio * median(d) (far outliers whose nearest points are other outliers, where
///   r_i is about 1).
/// In the spirit of the local outlier factor (Breunig et al. 2000) with a robust cut. A point
/// whose neighbours all coincide with it (r undefined) is kept.
/// Surface test (surface_sigmas > 0), for outliers near the surface at its density:
///   - each point's surface: over its 2k nearest others (the point excluded), a least-squares
///     plane refitted without those beyond 2.5 robust standard deviations, then a quadric height
///     over that plane refitted without those whose deleted residual (residual / (1 - leverage))
///     is beyond 2.5 robust standard deviations; v_i = its residual variance (over n - 6 and
///     corrected for the trim);
///   - noise s_i: square root of the mean of v over p_i and its neighbours (those within 4 times
///     their median), averaged over the point and its neighbours 3 times, at least
///     surface_floor * median of the neighbours' d;
///   - surface distance h_i = median over the neighbours of p_i's distance to their surfaces
///     (between two sheets p_i's own fit would run between them);
///   - p_i is off the surface iff h_i > surface_sigmas * s_i where the neighbourhoods are
///     surfaces (flatness of the planes, smallest over middle eigenvalue, averaged like the
///     noise, <= 0.35),
///     or, for a sparse point (d_i > min_ratio * median(d)), also when its own neighbours form
///     no surface (a group of outliers inside a closed part);
///   - an off-surface point is dropped unless it has 2 or more off-surface neighbours and is
///     not sparse (a structure: vegetation or walls of an aerial scan);
///   - then once more over the points kept (an outlier whose neighbours were partly outliers now
///     has the surface around it).
/// Where the noise is wider than the neighbourhoods (flatness > 0.35, as on CGAL's
/// sphere_20k.xyz: noise of 3 spacings) the surface test keeps the points; raise k there.
/// Measured (bench/clean/outlier_sweep.sh, docs/clean.md): meshes sampled at 200k points with
/// noise 0.1 % of the diagonal along the normal and 1 % uniform outliers: at most 0.2 % of the
/// outliers beyond 5 sigma left, at most 0.1 % of the surface samples removed.
/// `threshold` in the result is the density test's ratio cut (mean spacings of the
/// neighbourhood, dimensionless). Memory O(k N) (the neighbour lists and surfaces); parallel
/// passes (oneTBB), about 7-9x the density test's time with the surface test. Throws UsageError
/// for k < 2, min_ratio <= 1, mad_sigmas <= 0, far_ratio <= 1, surface_sigmas < 0,
/// surface_floor <= 0, fewer than k + 1 points; CancelledError when `progress` returns false.
OutlierResult remove_local_outliers(const PointCloud& cloud, const LocalOutlierParams& params = {}, const KdTree* tree = nullptr,
                                    const ProgressCallback& progress = {});

struct RadiusOutlierParams {
  int min_neighbours = 4;           // keep a point with at least this many other points
                                    // within the radius, >= 1
  Length radius = Length::spacings(4.0);  // cloud units or mean spacings, > 0
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<RadiusOutlierParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Radius outlier removal: drops points with fewer than `min_neighbours` other points within
/// `radius` (inclusive) -- isolated "drift" points floating above a surface. Same decision as
/// Open3D's remove_radius_outlier(nb_points = min_neighbours, radius) (which counts the point
/// itself and keeps count > nb_points). On an evenly sampled surface a disc of radius 4
/// spacings holds about 12 points, so the default keeps sparse borders. Parallel (oneTBB);
/// stops counting at min_neighbours + 1. Throws UsageError for min_neighbours < 1, a radius
/// not > 0, fewer than 2 points; CancelledError on cancel.
OutlierResult remove_radius_outliers(const PointCloud& cloud, const RadiusOutlierParams& params = {},
                                     const KdTree* tree = nullptr, const ProgressCallback& progress = {});

struct RansacOutlierParams {
  int k = 24;                         // neighbourhood size (point included), >= 4
  Length distance = Length::spacings(1.0);  // plane distance, cloud units or mean spacings, > 0
  int iterations = 50;                // random planes tried per point, >= 1
  double min_support = 0.3;           // a plane counts when at least this fraction of the
                                      // neighbourhood lies within `distance` of it, in (0, 1]
  double min_relative_support = 0.7;  // a plane through the point holding this fraction of the
                                      // neighbourhood, or scoring this fraction of the dominant
                                      // plane, keeps it (see below), in [0, 1]
  std::uint64_t seed = 1;             // random planes depend only on the seed, the point's
                                      // coordinates and its neighbours (not on point order)
  bool primitives = true;             // also detect planes, spheres, cylinders and cones
                                      // (detect_primitives, epsilon = distance) and judge the
                                      // points they explain by them (see below)
  double primitive_band = 2.0;        // a point amid a primitive's inliers farther than this
                                      // many `distance` from it is an outlier, > 0
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<RansacOutlierParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// Local RANSAC outlier removal (Fischler & Bolles 1981). For each point p, planes through 3
/// random points among its k nearest neighbours (p itself excluded) are tried. A plane's
/// support is the number of neighbours within `distance` of it, its score the MSAC sum of
/// 1 - r^2 / distance^2 over them (a surface, residuals at the noise level, outscores a plane
/// cutting across a crease). The best-scoring plane, refitted by least squares to its inliers,
/// is the neighbourhood's dominant plane. A plane that passes within 2 * distance of p and
/// holds min_support of the neighbours is refitted to its inliers too; such a refitted plane
/// "passes near" p when p lies within clamp(4 * RMS residual of its inliers, distance,
/// 2 * distance) of it (the band widens with the local noise) and p's foot lies within 2.5
/// in-plane standard deviations of the inliers' centroid (1.6 at a cube corner; a plane
/// supported only far from p does not count). p is kept iff
///   - a refitted plane through p holds min_relative_support of all neighbours, or
///   - the dominant plane passes near p, or
///   - a refitted plane through p scores min_relative_support of the dominant plane and holds
///     half of min_support of the neighbours off the dominant plane (a crease's other face).
/// A drift point floating above a surface is passed only by steep planes through a strip of
/// the surface below it: the strip's own least-squares plane is the surface (far from p), and
/// what such a plane holds lies on the dominant plane; a few drift points together (clusters of
/// up to about 6 of 24) do not make a plane of their own either.
/// Measured (tests/clean/remove_outliers_test.cpp, default parameters): drift 3..15 spacings
/// above a cube with noise 0.2 spacing: precision 1.000, recall 1.000, no point within 2
/// spacings of an edge or 3 of a corner removed; noise 0.5 spacing: 0.980 / 0.980. Limit: within
/// about 2 spacings of a cube corner a plane cutting the corner can hold 20 of 23 neighbours, and
/// a few such points go (6 of about 330 over 8 seeded cubes).
/// With `primitives` (the default), efficient RANSAC primitives (detect_primitives with
/// epsilon = distance, its other parameters at their defaults; normals are estimated on a copy
/// when the cloud has none) decide first: a point assigned to a primitive is kept (a sphere or
/// thin cylinder curves too much for local planes); a point 3/4 of whose neighbours are
/// inliers of one primitive but which lies farther than primitive_band * distance from every
/// such primitive is an outlier (a drift point above a curved surface, which a local plane
/// through a curved strip may pass); the other points, free-form parts no primitive explains
/// included, are decided by the local planes above, so the mode removes no fewer outliers.
/// Measured (same tests, primitives on vs off): plane + sphere (r 0.3) + cylinder (r 0.15)
/// with noise 0.4 spacing and 2 % drift: precision 1.000 / 1.000, recall 1.000 / 0.984; cube,
/// noise 0.5: 0.985 / 0.980, recall 0.990 / 0.980; drift clusters of 6: recall 0.983 / 0.908.
/// Per-point random streams are seeded from `seed` and the point's coordinates, so the result is
/// reproducible and independent of point order and thread count. Parallel (oneTBB),
/// O(N k iterations), no allocation per point. `threshold` in the result is `distance`.
/// Throws UsageError for k < 4, iterations < 1, a distance not > 0, min_support outside (0, 1],
/// min_relative_support outside [0, 1], primitive_band <= 0, fewer than 4 points;
/// CancelledError on cancel.
OutlierResult remove_ransac_outliers(const PointCloud& cloud, const RansacOutlierParams& params = {},
                                     const KdTree* tree = nullptr, const ProgressCallback& progress = {});

/// The points at `kept` with every attribute and field (a PointCloud::select for uint32
/// indices). Throws UsageError for an index out of range.
PointCloud keep_points(const PointCloud& cloud, std::span<const std::uint32_t> kept);

}  // namespace pointsurf
