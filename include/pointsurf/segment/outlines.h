// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Outlines of planar segments: alpha-shape boundaries, holes included, as closed polylines.
#include <cstddef>
#include <cstdint>
#include <span>
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

struct OutlineResult {
  std::vector<SegmentOutline> outlines;  // by segment label
  std::size_t nonplanar = 0;             // segments skipped as not planar
  double alpha_used = 0.0;               // cloud units
};

/// For each segment of `labels` (one per point, -1 none) of at least `min_points` points that
/// is planar: its points projected onto their least-squares plane, the regularized 2D alpha
/// shape of squared radius alpha^2 (Edelsbrunner, Kirkpatrick, Seidel 1983; CGAL
/// Alpha_shape_2), whose boundary edges are chained into closed loops; a loop inside another is
/// a hole; each loop is then simplified by Douglas-Peucker (Douglas, Peucker 1973). Throws UsageError for a bad parameter or a label count other than the point count.
/// Deterministic; thread-safe (reads its inputs).
OutlineResult outline_planar_segments(const PointCloud& cloud, std::span<const std::int32_t> labels, const OutlineParams& params = {});

}  // namespace pointsurf
