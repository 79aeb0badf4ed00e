// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// simplify_regional as a phase object: the shared state as named members, one member function
// per phase, so that each phase can be run alone on a small cloud or on hand-made state.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <tuple>
#include <vector>

#include "core/detail/progress_reporter.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf::detail {

/// A greedy cluster of the points of one region cell by normal.
struct RegionCluster {
  Vector3d normal_sum = Vector3d::Zero();  // sign-aligned sum of member normals
  Vector3d mean = Vector3d::Zero();        // unit mean normal
  Vector3d offset_sum = Vector3d::Zero();  // sum of (p - base)
  Vector3d centroid = Vector3d::Zero();    // relative to base
  double radius = 0.0;
  std::size_t count = 0;
};

/// The plane of a cluster of at least 3 points.
struct ClusterPlane {
  Vector3d centroid;  // relative to the bounding-box minimum
  Vector3d normal;    // unit
  double radius;      // largest distance of a member to the centroid
};

/// A flat point in its cluster's grid cell.
struct FlatCell {
  std::uint64_t cluster;             // the normal class of the point's cluster
  std::array<std::int64_t, 3> cell;  // grid cell of the cluster's own size
  std::uint32_t point;
  bool same_cell(const FlatCell& o) const { return cluster == o.cluster && cell == o.cell; }
  bool operator<(const FlatCell& o) const { return std::tie(cluster, cell, point) < std::tie(o.cluster, o.cell, o.point); }
};

/// Per-thread scratch for one region cell, reused across cells (no per-point allocation).
struct CellScratch {
  std::vector<std::uint32_t> members;
  std::vector<std::uint32_t> cluster;  // per member
  std::vector<RegionCluster> clusters;
};

/// The orientation class of a cluster's unit mean normal `m` (unoriented): the axis of its
/// largest component and the other two components in three bins each, 27 classes of about 35
/// degrees (a cube map); 27 for a zero normal.
std::uint64_t normal_class(const Vector3d& m);

/// The state and phases of simplify_regional: clusters by position (region cells) and normal,
/// a feature factor F per point, the feature candidates, and the flat points thinned on a grid
/// per normal class.
class RegionalSimplification {
public:
  /// Over `cloud` (at least 3 points) and `params` (validated); both must outlive the object.
  RegionalSimplification(const PointCloud& cloud, const RegionalParams& params);
  RegionalSimplification(const PointCloud&, RegionalParams&&) = delete;  // it would dangle
  RegionalSimplification(PointCloud&&, const RegionalParams&) = delete;

  /// Reads the cloud and `tree` (or builds one); produces `t`, the `box`, the `spacing` and the
  /// `surface` (normals and variation: the cloud's, or estimated, reporting on [0, 0.6]).
  void measure_surface(const KdTree* tree, const ProgressCallback& progress);
  /// Reads the surface; clusters each region cell by normal and produces `visit_order`, the
  /// cells' `planes` and per point `cluster_key`, `cluster_normal`, `base_terms`, `own_delta`.
  void cluster_regions(ProgressReporter& reporter);
  /// Reads the planes and per-point terms; produces `crease` (nearness to another cluster's
  /// plane in the 27 cells around) and the feature factor `factor`.
  void find_creases(ProgressReporter& reporter);
  /// Reads `factor`; produces `threshold`: the given one, or median + 3 MAD, at least 0.02.
  void choose_threshold();
  /// Reads `factor`, `threshold`, `crease` and the `feature` field; produces `boundary` and the
  /// feature `candidates` (at most the feature budget, by priority), ascending.
  void select_features();
  /// Reads the candidates and the non-candidates in `visit_order`; produces `kept_mask`: the
  /// candidates and one point per occupied cell and normal class of the flat points, the cell
  /// `d` solved for the target count.
  void thin_flat_areas(ProgressReporter& reporter);
  /// Reads `kept_mask`; adds the leftover points of highest F until the target count.
  void top_up();
  /// The kept points in input order, with their feature factor.
  SimplifyResult result() &&;

  // Inputs.
  const PointCloud& cloud;
  const RegionalParams& params;
  std::size_t n = 0;
  const ScalarField* feature_field = nullptr;  // the features module's marks, if any

  // The surface.
  std::optional<KdTree> own;
  const KdTree* t = nullptr;
  BoundingBox box;
  double spacing = 0.0;
  SurfaceProperties surface;

  // Clusters and the feature factor.
  GridCells regions;
  double cos_join = 0.0, crease_scale = 0.0, weight_sum = 0.0;
  std::vector<std::uint32_t> visit_order;           // cell by cell, inside a cell by position
  std::vector<std::vector<ClusterPlane>> planes;    // per region cell
  std::vector<std::uint64_t> cluster_key;           // per point: normal class of its cluster
  std::vector<Vector3d> cluster_normal;             // per point: its cluster's unit mean normal
  std::vector<float> base_terms, own_delta, crease;  // per point: variation + normal terms, own-plane and crease terms
  std::vector<float> factor;                        // per point: F

  // Selection.
  double threshold = 0.0;
  BoundaryResult boundary;
  std::vector<std::uint32_t> candidates;  // feature points, ascending
  bool by_cell = false;
  std::size_t wanted = 0;  // target count (0 by cell)
  std::vector<char> is_candidate, kept_mask;
  std::vector<std::uint32_t> flat;  // the other points, in visit order
  std::vector<FlatCell> cells;      // flat points by normal class and cell
  std::vector<std::size_t> starts;  // cells[starts[g] .. starts[g + 1]) hold group g
  double d = 0.0;                   // the flat points' cell
  SimplifyResult out;

private:
  void cluster_cell(std::size_t cell, CellScratch& s);
  void group_by_normal(CellScratch& s) const;
  void merge_small_clusters(CellScratch& s) const;
  void point_terms(const CellScratch& s);
  void crease_cell(std::size_t cell);
  std::size_t cells_around(std::size_t cell, std::array<std::size_t, 27>& around) const;
  bool marked(std::uint32_t i) const;
  bool rim(std::uint32_t i) const;
  bool before(std::uint32_t a, std::uint32_t b) const;
  std::size_t group_flat(double length);
  void keep_representatives();
};

}  // namespace pointsurf::detail
