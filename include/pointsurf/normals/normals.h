// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Normal estimation by PCA of local neighbourhoods and consistent orientation.
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"
#include "pointsurf/spatial/neighborhood.h"

namespace pointsurf {

struct NormalParams {
  NeighborhoodKind neighborhood = NeighborhoodKind::Knn;
  int k = 30;                       // neighbours per point (Knn, Hybrid), >= 3
  Length radius = Length::spacings(3.0);  // (Radius, Hybrid) cloud units or mean spacings, > 0
  bool keep_variation = true;       // add field "variation" = l0 / (l0 + l1 + l2), in [0, 1/3]
  bool keep_mean_distance = false;  // add field "mean_distance" (Float64, cloud units): mean
                                    // distance from the point to its neighbours, itself included,
                                    // the statistic of statistical outlier removal (see
                                    // statistical_outliers_from_distances): one kNN pass for both
  /// The neighbourhood fields as the one Neighborhood type (spatial/neighborhood.h).
  Neighborhood neighborhood_settings() const noexcept { return {neighborhood, k, radius}; }
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<NormalParams>& fields();
  /// Throws UsageError naming the first value out of range (k < 3 where k is used, a radius
  /// not > 0 where used). The one place these values are checked.
  void validate() const;
};

struct NormalResult {
  std::size_t degenerate = 0;   // points with fewer than 3 neighbours or a rank-deficient
                                // neighbourhood: their normal is (0, 0, 0) (smaller is better)
  double radius_used = 0.0;     // search radius actually used (Radius, Hybrid), cloud units

  /// The reported members (core/results.h).
  static const ResultTable<NormalResult>& results();
};

/// Estimates unit normals by PCA: the eigenvector of the smallest eigenvalue of each point's
/// neighbourhood covariance (Hoppe et al. 1992). Writes `cloud.normals` (N×3) and, when asked,
/// the field "variation". Sign is arbitrary (call orient_normals afterwards) except that
/// existing normals, if any, keep their side. Reuses `tree` if given (it must be built over
/// `cloud.positions`; kNN neighbourhoods use a voxel grid, with the tree only for the rare
/// points whose neighbours lie beyond the grid's rings). Parallel (oneTBB) in spatial order;
/// throws UsageError for k < 3, a
/// negative radius or fewer than 3 points; CancelledError when `progress` returns false.
NormalResult estimate_normals(PointCloud& cloud, const NormalParams& params = {}, const KdTree* tree = nullptr,
                              const ProgressCallback& progress = {});

enum class Orientation {
  None,        // keep the PCA signs
  Viewpoint,   // each normal points towards `viewpoint` (scanner position)
  Direction,   // each normal has a positive dot product with `direction`
  Mst,         // consistent propagation over a minimum spanning tree (Hoppe 1992)
};
/// "mst", "viewpoint", "direction", "none".
const EnumNames<Orientation>& orientation_names();

struct OrientParams {
  Orientation method = Orientation::Mst;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  // cloud units (Viewpoint)
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ(); // any length > 0 (Direction)
  int k = 10;                                           // kNN graph degree (Mst), >= 1
  /// Key, unit, range and doc of each field (core/fields.h): orient, viewpoint, direction, orient_k.
  static const FieldTable<OrientParams>& fields();
  /// Throws UsageError for a non-finite viewpoint (Viewpoint), a zero or non-finite direction
  /// (Direction) or k < 1 (Mst).
  void validate() const;
};

struct OrientResult {
  std::size_t components = 0;   // connected components of the graph, after joining (Mst)
  std::size_t flipped = 0;      // normals whose sign changed
  std::vector<std::string> warnings;  // Mst: a close vote on a component's sign (see orient_normals)

  /// The reported members (core/results.h) of an orientation by `method`: the components with
  /// Mst only.
  static const ResultTable<OrientResult>& results(Orientation method);
};

/// Orients `cloud.normals` (which must be present) consistently. Mst (Hoppe et al. 1992):
/// builds the Riemannian graph, the symmetric kNN graph plus the shortest edges joining its
/// components (the Euclidean MST's edges between them; components further apart than 3 kNN
/// reaches stay apart as separate objects), with edge weights 1 - |ni·nj| + 0.3 x length in kNN
/// reaches (smooth paths first, short steps among them), takes its minimum spanning forest,
/// and propagates the sign along it from one seed per connected component. Each
/// component's global sign is then decided by all its points, in this order:
///  - classified: a component with points of LAS class 2 in a field "classification" is
///    terrain, and its ground points face up (the sum of their n_z is positive);
///  - terrain-like: a mostly horizontal open sheet (mean |n_z| >= 0.7, mean unit normal at
///    least 0.5 long), or a component that is open, level and low whatever stands on it: of
///    its xy columns (2 kNN reaches wide) holding two points or more, at least 15 % hold a
///    single layer (closed surfaces: a top and a bottom over each), the lowest points of the
///    columns have mean |n_z| >= 0.6, and its z extent is at most half its larger xy extent.
///    Terrain faces up (+z), the convention of aerial and ground LiDAR: the lowest point of
///    each column (the ground, under trees, eaves and bridges) votes with its n_z. Inside
///    terrain, smooth level regions (cut at creases > 45 degrees and where a normal within 45
///    degrees of vertical meets one that is not) that face down are turned up (roofs joined
///    to the ground only through walls or trees);
///  - other components face outward: sum n·(p - centroid) > 0, which holds for closed surfaces
///    and for single views of convex objects.
/// A vote whose winning side holds less than 60 % of its weight (|n_z| for up, |n·(p - c)|
/// for outward) on a component of at least 1 % of the points is close: OrientResult::warnings
/// says so (a single vertical wall, with no inside and no up, scores 50 %).
/// For a scan whose sensor position is known, Viewpoint is the safer choice (the positions of
/// an E57 file's scanners are not kept in the cloud).
/// Memory O(k N), no dense structure; graph construction parallel. Reuses `tree` if given
/// (built over `cloud.positions`). Throws UsageError on missing normals or bad parameters;
/// CancelledError when `progress` returns false.
OrientResult orient_normals(PointCloud& cloud, const OrientParams& params = {}, const KdTree* tree = nullptr,
                            const ProgressCallback& progress = {});

/// How far `normals` agree with `reference`, one of each per point (sizes may differ: the
/// first min(sizes) points are compared). Points where either normal is zero or not finite are
/// left out. Thread-safe (reads only).
struct NormalAgreement {
  std::size_t compared = 0;     // points where both normals have a direction
  std::size_t agreeing = 0;     // of those, the ones with a positive dot product (larger is better)
  double share = 0.0;           // agreeing / compared, in [0, 1] (1 when compared == 0; larger is better)
  double mean_angle_deg = 0.0;  // mean angle between the two lines, sign ignored, in [0, 90] degrees (smaller is better)

  /// The reported members (core/results.h), the reference being the input's normals.
  static const ResultTable<NormalAgreement>& results();
};
NormalAgreement compare_normals(std::span<const Eigen::Vector3d> reference, std::span<const Eigen::Vector3d> normals);

/// Flips each normal of `cloud.normals` whose dot product with `reference[i]` is negative, so
/// that every new normal keeps the side of the one it replaces (a scan's own normals, for
/// instance). Zero normals on either side are left as they are. `reference` must hold one
/// normal per point; throws UsageError otherwise or when the cloud has no normals. O(N).
OrientResult orient_to_reference(PointCloud& cloud, std::span<const Eigen::Vector3d> reference);

/// Flips each normal of `cloud.normals` to face the scanner that recorded its point: scanner
/// `scan_of_point[i]` of `scanners` (positions, cloud units; an E57 scan's pose translation), or
/// scanners[0] for every point when `scan_of_point` is empty. A scan's points face their own
/// sensor, the one orientation that is right for interiors, overhangs and thin walls alike.
/// Zero normals and points at a scanner's position are left as they are. Throws UsageError when
/// the cloud has no normals, there is no scanner or a size differs; InputError naming the point
/// whose scan index is not one of the scanners. O(N).
OrientResult orient_to_scanners(PointCloud& cloud, std::span<const Eigen::Vector3d> scanners, std::span<const double> scan_of_point = {});

}  // namespace pointsurf
