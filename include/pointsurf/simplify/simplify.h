// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Point cloud simplification (and adaptive resampling): fewer points that still describe the
// surface. Six methods, one result type:
//   simplify_grid                uniform voxel grid, centroid or nearest sample per cell
//   simplify_random              seeded uniform random subset
//   simplify_curvature           curvature-weighted random subset (keeps high curvature)
//   simplify_regional            clusters by position and normal, a feature factor per point
//                                keeps edges and thins flat areas
//   simplify_curvature_distance  split by curvature, Poisson-disk thinning of each part with
//                                its own distance
//   resample_lfs                 spacing proportional to the local feature size, thinning
//                                dense and filling sparse regions
// Every method takes the size of its output through a SimplifyTarget.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

/// How many points to keep. Exactly one way is used, in this order of precedence:
///  - `cell > 0`: a length (cloud units): the grid cell for the grid method, the Poisson-disk
///    distance of flat/low-curvature points for regional and curvature-distance, the target
///    spacing at the median local feature size for lfs. The count follows from the data.
///    Not accepted by random and curvature (a UsageError).
///  - `count > 0`: about `count` output points (exact for random, curvature and regional;
///    within about 2 % for the distance-based methods, which solve for a length).
///  - otherwise `ratio` in (0, 1]: about ratio × N output points.
struct SimplifyTarget {
  double ratio = 0.1;      // kept fraction of the input, in (0, 1]
  std::size_t count = 0;   // points wanted; 0: use ratio (or cell)
  double cell = 0.0;       // cloud units, >= 0; 0: use count or ratio
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<SimplifyTarget>& fields();
  /// Throws UsageError for a value out of its range (ratio where used, cell); the methods check
  /// the target against the cloud (and whether they take a cell).
  void validate() const;
};

/// The simplified cloud and where each of its points came from.
struct SimplifyResult {
  PointCloud cloud;                       // M output points with the input's normals, colours and fields
  std::vector<std::size_t> source_index;  // M: the input point it is (or, for averaged and
                                          // inserted points, the input point nearest to it)
  std::size_t input_points = 0;           // N
  std::size_t feature_points = 0;         // points kept because they are features (regional,
                                          // curvature-distance: the high-curvature part kept)
  std::size_t boundary_points = 0;        // rim points kept: boundary points of open surfaces
                                          // (regional: the angular-gap test), thinned along the rim
  std::size_t added_points = 0;           // new points inserted in sparse regions (lfs only)
  double length_used = 0.0;               // cloud units: the grid cell (grid), Poisson-disk
                                          // distance of the flat / low part (regional,
                                          // curvature-distance), spacing at the median LFS
                                          // (lfs); 0 for random and curvature
  double reduction() const noexcept {     // input / output points (higher: smaller output)
    return cloud.empty() ? 0.0 : double(input_points) / double(cloud.size());
  }
};

enum class GridMode {
  Centroid,  // one point per occupied cell at the mean of its points (normals averaged and
             // renormalised, colours and floating-point fields averaged; integer fields are
             // taken from the sample nearest to the mean): Open3D's voxel_down_sample
  Nearest,   // the input sample nearest to its cell's centroid, unchanged
};
/// "centroid", "nearest".
const EnumNames<GridMode>& grid_mode_names();

struct GridParams {
  SimplifyTarget target;
  GridMode mode = GridMode::Centroid;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<GridParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Uniform grid simplification. Cells are cubes of side `cell` anchored at the bounding box
/// minimum minus half a cell (Open3D's convention, so both give the same centroids). With a
/// ratio or count target the cell is solved for (a few secant steps on log count vs log cell;
/// the count is then approximate, within about 3 %). Cells are found by a parallel sort of 64-bit cell
/// keys, not a hash map; output in ascending cell key (x fastest). Offsets from the grid
/// origin keep georeferenced coordinates exact. O(N log N); parallel (oneTBB); thread-safe
/// on distinct outputs. Throws UsageError for a bad target or an empty cloud; CancelledError
/// when `progress` returns false.
SimplifyResult simplify_grid(const PointCloud& cloud, const GridParams& params = {}, const ProgressCallback& progress = {});

struct RandomParams {
  SimplifyTarget target;       // ratio or count (cell is rejected)
  std::uint64_t seed = 42;     // same seed, same input order: same output
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<RandomParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// A uniformly random subset of exactly the target count, kept in input order (seeded
/// Fisher-Yates). O(N). Throws UsageError for a bad target or an empty cloud.
SimplifyResult simplify_random(const PointCloud& cloud, const RandomParams& params = {});

struct CurvatureSimplifyParams {
  SimplifyTarget target;       // ratio or count (cell is rejected)
  int k = 20;                  // neighbours for normals/variation when the cloud has no field
                               // "variation" (>= 3)
  double flat_weight = 0.1;    // weight of a flat point relative to the mean variation, >= 0:
                               // w_i = variation_i + flat_weight × mean(variation)
  std::uint64_t seed = 42;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<CurvatureSimplifyParams>& fields();
  /// Throws UsageError naming the first value out of range (the target is checked against
  /// the cloud by the algorithm): the one place these values are checked.
  void validate() const;
};

/// Curvature-based simplification: a weighted random subset of exactly the target count, the
/// probability of keeping a point growing with its surface variation (Pauly et al. 2002,
/// "Efficient simplification of point-sampled surfaces", variation as curvature measure),
/// drawn by weighted sampling without replacement (Efraimidis & Spirakis 2006: the largest
/// u^(1/w)). High-curvature points are kept more often, not always. Uses the field
/// "variation" when present, else PCA with `k` neighbours (through `tree` when given; it must
/// be built over cloud.positions). Parallel; throws UsageError for bad parameters.
SimplifyResult simplify_curvature(const PointCloud& cloud, const CurvatureSimplifyParams& params = {}, const KdTree* tree = nullptr,
                                  const ProgressCallback& progress = {});

struct RegionalParams {
  SimplifyTarget target;
  int k = 16;                          // neighbours for normals/variation when missing (>= 3)
  Length region_size = Length::spacings(10.0);  // cluster cell size, cloud units or mean spacings, > 0
  double region_angle_deg = 30.0;      // a point joins a cluster of its cell when its normal
                                       // is within this angle of the cluster's mean, (0, 90]
  double variation_weight = 1.0;       // weights of the three feature-factor ingredients, >= 0,
  double normal_weight = 1.0;          //   not all zero (see the formula below)
  double distance_weight = 1.0;
  double feature_threshold = -1.0;     // F above which a point is a feature candidate, [0, 1];
                                       // < 0: derived (median + 3 × 1.4826 MAD of F, at least 0.02)
  double max_feature_share = 0.5;      // at most this share of the output are feature points, (0, 1]
  bool keep_boundary = false;          // true: thin the rims of open surfaces (the angular-gap
                                       // test) on a grid of half the flat cell (the paper's step;
                                       // measured to raise the area change on open scans, see
                                       // docs/simplify.md); false: rim points are flat points, and
                                       // no boundary test runs
  double spacing = 0.0;                // the cloud's mean spacing, cloud units, >= 0; 0: measured
                                       // (normals and the field "variation" are likewise taken
                                       // from the cloud when it has them)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<RegionalParams>& fields();
  /// Throws UsageError naming the first value out of range (the target is checked against
  /// the cloud by the algorithm): the one place these values are checked.
  void validate() const;
};

/// Regional simplification: cluster by position and normal, decide per point by a feature
/// factor, keep feature (edge) points, thin flat areas.
/// Clusters: the cloud is cut into cubes of side region_size (in mean spacings by default); inside each cube
/// points are grouped greedily (in spatial order) with the first group whose running mean
/// normal is within region_angle_deg (unoriented); clusters with less than 20 % of their cell's
/// points (transitions such as the points along an edge) then join the large cluster nearest in
/// normal. Per cluster C: centroid c_C, unit mean
/// normal m_C (sign-aligned sum), radius r_C (largest distance of a member to c_C).
/// Feature factor of point i in C, each ingredient in [0, 1]:
///   sigma_i = 3 × variation_i                       (surface variation, 1/3 is the maximum)
///   theta_i = angle(n_i, ±m_C) / 90°                (normal deviation from the cluster mean)
///   delta_i = max( min(1, |(p_i - c_C)·m_C| / (0.5 r_C)),             (off its cluster's plane)
///                  max_P 1 - min(1, |(p_i - c_P)·m_P| / (2 s)) )       (on another plane: a crease)
///     where P runs over the planes (centroid c_P, mean normal m_P) of the greedy clusters of
///     the same cell with at least 3 points and a normal more than region_angle_deg from m_C,
///     and s is the mean spacing: a point within 2 s of such a plane lies where two regions meet
///   F_i = (wv sigma_i + wn theta_i + wd delta_i) / (wv + wn + wd)
/// Kept points: those with field "feature" > 0 (from the features module) when present, and
/// those with F >= threshold; when they exceed max_feature_share of the target, the marked ones
/// first, then by decreasing F + c_i (c_i the crease part of delta_i: of the band of high-F
/// points along an edge, those on the crease first).
/// The rest of the budget goes to the other points, thinned per cluster orientation: the
/// clusters of one normal class (27 classes of about 35 degrees, a cube map of the cluster's mean
/// normal) share one grid of cell d, one point per occupied cell and class (the sample nearest
/// the centroid of the cell's points of that class); rim points (keep_boundary: boundary points
/// of open surfaces by `detect_boundary_points`, the angular-gap test with its defaults, off a
/// crease; counted in `boundary_points`) on their own grid of cell d / 2. d is solved for the
/// remaining count; the count is then made exact by dropping the representatives of the least
/// populated cells or adding the highest-F leftover points.
/// Follows the regional method of the paper (SPEC C6; docs/simplify.md maps each step); the
/// paper names the feature factor without a formula, the one above is ours. Reuses `tree`
/// (built over cloud.positions) for normals, spacing and the boundary test; builds one when none
/// is given. Parallel; throws UsageError for bad parameters; CancelledError when `progress`
/// returns false.
SimplifyResult simplify_regional(const PointCloud& cloud, const RegionalParams& params = {}, const KdTree* tree = nullptr,
                                 const ProgressCallback& progress = {});

struct CurvatureDistanceParams {
  SimplifyTarget target;                // fixes the low-curvature distance d_low
  int k = 16;                           // neighbours for variation when missing (>= 3)
  double split_quantile = 0.9;          // points with variation above this quantile form the
                                        // high part, (0, 1)
  double high_to_low_distance = 0.4;    // d_high = this × d_low, (0, 1]
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<CurvatureDistanceParams>& fields();
  /// Throws UsageError naming the first value out of range (the target is checked against
  /// the cloud by the algorithm): the one place these values are checked.
  void validate() const;
};

/// Curvature-distance simplification: split the points by surface variation into a high and a
/// low part, then thin each part by greedy Poisson-disk sampling in the tree's spatial order
/// with its own distance (a kept point removes the not yet visited points of its own part
/// within d of it). With a ratio or count target d_low is solved for. Serial greedy pass over
/// one shared kd-tree (radius queries only from kept points). Throws UsageError for bad
/// parameters; CancelledError when `progress` returns false.
SimplifyResult simplify_curvature_distance(const PointCloud& cloud, const CurvatureDistanceParams& params = {},
                                           const KdTree* tree = nullptr, const ProgressCallback& progress = {});

struct LfsParams {
  SimplifyTarget target;                // sets the spacing scale lambda (see below)
  int k = 16;                           // neighbours for normals (>= 3)
  double adaptivity = 4.0;              // LFS clamped to [median / a, median × a], a >= 1
  int fill_neighbours = 6;              // kNN edges tested for gaps when filling (>= 1)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<LfsParams>& fields();
  /// Throws UsageError naming the first value out of range (the target is checked against
  /// the cloud by the algorithm): the one place these values are checked.
  void validate() const;
};

/// Local feature size of every point (Amenta, Bern & Kamvysselis 1998): the distance to the
/// medial axis, approximated by the nearest Voronoi pole (`voronoi_poles`, inner and outer) of
/// any sample. Poles closer to their own sample than its nearest neighbour are noise, not the
/// medial axis, and are not used. A distance to a set of points, the result is 1-Lipschitz
/// (|LFS(p) - LFS(q)| <= |p - q|). A sphere of radius R gives R; a plate of thickness 2h gives h
/// on its faces. +infinity where no pole is left (all points coplanar: a plane has no medial
/// axis). Uses `tree` (over cloud.positions) when given. Throws UsageError for fewer than 4
/// points; InputError for a non-finite coordinate.
std::vector<double> local_feature_size(const PointCloud& cloud, const KdTree* tree = nullptr);

/// Local-feature-size adaptive resampling. LFS_i from `local_feature_size` (the bounding-box
/// diagonal where it is infinite). Target spacing t_i = lambda × clamp(LFS_i, median/a,
/// median×a), lambda solved for the target (cell: the spacing at the median LFS). Gaps: along
/// each of the fill_neighbours nearest-neighbour edges longer than t (and within 30 degrees of
/// both endpoints' tangent planes: an edge across a thin part joins two sheets, not a gap),
/// candidates are inserted every 0.25 t, blended between the two endpoints' tangent planes
/// (normal interpolated; colour interpolated; fields copied from the nearer endpoint). Then a
/// greedy Poisson-disk pass over input and inserted points together, in one spatial order, with
/// per-point radius t; a kept point removes only points nearer its tangent plane than its LFS
/// (beyond that lies the other side of the medial axis: the two faces of a thin plate are never
/// merged). A non-uniform cloud comes out uniform in flat regions and denser where the LFS is
/// small. Uses `tree` for the input. Throws UsageError for bad parameters; CancelledError when
/// `progress` returns false.
SimplifyResult resample_lfs(const PointCloud& cloud, const LfsParams& params = {}, const KdTree* tree = nullptr,
                            const ProgressCallback& progress = {});

}  // namespace pointsurf
