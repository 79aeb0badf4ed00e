// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Outlines of planar segments: alpha-shape boundaries, holes included, as closed polylines.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/polyline.h"

namespace pointsurf {

struct OutlineParams {
  Length alpha = Length::spacings(5.0);  // alpha radius (the largest empty disc that still cuts
                                        // in), cloud units or mean spacings, > 0 (uniform random
                                        // samples of 40k points leave empty discs of about 3.7
                                        // mean spacings)
  double max_rms_in_spacings = 0.5;     // a segment is planar when the RMS distance of its
                                        // points to their least-squares plane is at most this
                                        // many mean spacings
  double simplify_in_spacings = 2.0;    // loops are simplified (Douglas-Peucker) to within this
                                        // many mean spacings, which removes the zigzag of the
                                        // alpha-shape boundary (0: none)
  double offset_in_spacings = 1.0;      // loops are moved this many mean spacings away from
                                        // the segment's points (outer loops out, holes in): the
                                        // outermost samples lie inside the true edge by about
                                        // that much (0: through the samples)
  std::size_t min_points = 30;          // segments with fewer points get no outline
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<OutlineParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

struct SegmentOutline {
  std::int32_t segment = -1;                       // the label it outlines
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // of the segment's plane
  std::vector<Polyline> loops;                     // closed, by enclosed area, largest first
  std::vector<std::uint8_t> hole;                  // per loop: 1 when it lies inside another
  std::vector<std::int32_t> outer;                 // per loop: for a hole, the index of the loop
                                                   // it lies inside; -1 for an outer loop
  double area = 0.0;                               // outer loops' areas minus the holes', units^2
  double perimeter = 0.0;                          // all loops' lengths, cloud units
};

/// A segment's own plane, when the segmentation fitted one (RANSAC): the outline uses it instead
/// of a least-squares plane, and the segment counts as planar when the RMS distance of its points
/// to it is at most 1.5 `band` (RANSAC's epsilon: its inliers lie within it of the candidate
/// plane, and a little farther from the refitted one it reports).
struct SegmentPlane {
  std::int32_t segment = -1;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();    // on the plane, cloud units
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit
  double band = 0.0;                                  // cloud units
};

enum class SkipReason : unsigned char { TooSmall, NotPlanar };

/// A segment that got no outline, and why.
struct SkippedSegment {
  std::int32_t segment = -1;
  std::size_t points = 0;
  SkipReason reason = SkipReason::NotPlanar;
  double rms = 0.0;       // NotPlanar: RMS distance to its plane, cloud units
  double threshold = 0.0; // NotPlanar: the RMS it had to stay within, cloud units
};

struct OutlineResult {
  std::vector<SegmentOutline> outlines;  // by segment label
  std::size_t nonplanar = 0;             // segments skipped as not planar
  std::size_t too_small = 0;             // segments skipped for fewer than min_points points
  std::vector<SkippedSegment> skipped;   // each skipped segment, by label
  double alpha_used = 0.0;               // cloud units
  double spacing = 0.0;                  // the cloud's mean spacing, cloud units
};

/// For each segment of `labels` (one per point, -1 none) of at least `min_points` points that
/// is planar: its points projected onto its plane (its own from `planes` when listed there,
/// else their least-squares plane), the regularized 2D alpha
/// shape of squared radius alpha^2 (Edelsbrunner, Kirkpatrick, Seidel 1983; CGAL
/// Alpha_shape_2), whose boundary edges are chained into closed loops; a loop inside another is
/// a hole; each loop is then simplified by Douglas-Peucker (Douglas, Peucker 1973). Throws UsageError for a bad parameter or a label count other than the point count.
/// Deterministic; thread-safe (reads its inputs).
OutlineResult outline_planar_segments(const PointCloud& cloud, std::span<const std::int32_t> labels, const OutlineParams& params = {},
                                      std::span<const SegmentPlane> planes = {});

/// "3 of 7 segments have no outline: 2 not planar (RMS to their plane 0.61-1.3 mean spacings,
/// above 0.5), 1 with fewer than 30 points"; empty when none was skipped.
std::string describe_skipped(const OutlineResult& result, std::size_t segments, const OutlineParams& params);

}  // namespace pointsurf
