// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Segmentation of a point cloud into regions: region growing by normal angle and curvature,
// Euclidean clusters, and connected regions of one HK surface type. (Primitives by RANSAC:
// shape/primitives.h.) Every function returns one label per point, -1 unassigned, segments
// numbered by size, largest first (ties: the lexicographically smallest point first), so the
// labels do not depend on the order of the points.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct SegmentResult {
  std::vector<std::int32_t> labels;  // N: segment index, -1 unassigned
  std::vector<std::size_t> sizes;    // points per segment, descending
  std::size_t unassigned = 0;        // points in no segment (in segments below min_points)
};

struct RegionGrowingParams {
  int k = 16;                    // neighbours per point (the graph's edges), >= 3
  double max_angle_deg = 8.0;    // largest angle between the normals of two neighbours in one
                                 // region, degrees, in (0, 90]
  double max_variation = 0.05;   // a point whose surface variation l0 / (l0 + l1 + l2) exceeds
                                 // this joins a region but does not extend it, in [0, 1/3]
  bool use_features = true;      // points with a non-zero "feature" field (features stage)
                                 // join a region but do not extend it
  std::size_t min_points = 10;   // fewest points of a segment; smaller ones are unassigned
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<RegionGrowingParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Region growing over the kNN graph (Rabbani, van den Heuvel, Vosselmann 2006; PCL's
/// RegionGrowing): seeds in order of increasing surface variation; a region takes a neighbour
/// whose normal is within `max_angle_deg` of the current point's (sign free) and grows on from
/// it when its variation is at most `max_variation` and it is not a feature point. Needs normals
/// (UsageError otherwise; zero normals stay unassigned). Reuses `tree` if given.
/// Deterministic; thread-safe (reads `cloud`).
SegmentResult segment_region_growing(const PointCloud& cloud, const RegionGrowingParams& params = {}, const KdTree* tree = nullptr,
                                     const ProgressCallback& progress = {});

struct EuclideanParams {
  Length radius = Length::spacings(3.0);  // points closer than this are in one cluster, cloud
                                          // units or mean spacings, > 0
  std::size_t min_points = 10;       // fewest points of a cluster; smaller ones are unassigned
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<EuclideanParams>& fields();
  void validate() const;
};

/// Euclidean clustering: the connected components of the graph joining points within
/// `radius` (PCL's EuclideanClusterExtraction; DBSCAN with min_samples 1). Reuses `tree` if
/// given. Deterministic; thread-safe (reads `cloud`).
SegmentResult segment_euclidean(const PointCloud& cloud, const EuclideanParams& params = {}, const KdTree* tree = nullptr);

struct SurfaceTypeParams {
  int k = 12;                   // neighbours per point (the graph's edges), >= 2
  std::size_t min_points = 10;  // fewest points of a region; smaller ones are unassigned
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<SurfaceTypeParams>& fields();
  void validate() const;
};

/// Connected regions of one HK surface type: the components of the kNN graph restricted to
/// edges between points with the same value of the "surface_type" field (shape/curvature.h;
/// type 0, undefined, is never joined). Throws UsageError when the field is missing.
/// Deterministic; thread-safe (reads `cloud`).
SegmentResult segment_surface_types(const PointCloud& cloud, const SurfaceTypeParams& params = {}, const KdTree* tree = nullptr);

/// Numbers the groups of `groups` (any ids, -1 none) by size, largest first, ties by their
/// lexicographically smallest point; groups below `min_points` become -1.
SegmentResult number_segments(std::span<const Eigen::Vector3d> positions, std::span<const std::int64_t> groups, std::size_t min_points);

}  // namespace pointsurf
