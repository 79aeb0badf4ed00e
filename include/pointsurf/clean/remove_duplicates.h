// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Exact and near duplicate points: found, then merged into the first point of each group.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct DuplicateParams {
  bool exact = false;                 // true: only points with identical coordinates are
                                      // duplicates (distance 0); `distance` is then ignored
  Length distance = Length::spacings(0.1);  // cloud units or mean spacings, > 0 (not exact)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<DuplicateParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

struct DuplicateResult {
  std::vector<std::uint32_t> kept;            // ascending indices of the points kept (K)
  std::vector<std::uint32_t> representative;  // N: the kept point each point merges into
                                              // (itself when kept)
  std::size_t removed = 0;                    // N - K duplicates merged away
  double distance_used = 0.0;                 // cloud units (0 for exact)
  double max_distance = 0.0;                  // largest distance from a removed point to its
                                              // representative, cloud units (<= distance_used)

  /// The reported members (core/results.h).
  static const ResultTable<DuplicateResult>& results();
};

/// Finds duplicates: scanning points by index, a point within `distance` (inclusive) of an
/// earlier kept point merges into the earliest such point; otherwise it is kept. So the first
/// point of a group by index survives, no two kept points are closer than `distance`, and for
/// exact duplicates the result does not depend on point order beyond which copy survives.
/// Neighbour search in parallel (oneTBB), then one serial O(N + pairs) pass. `tree`
/// (optional) must be built over `cloud.positions`. Throws UsageError for a distance not > 0
/// (unless exact), an empty cloud; CancelledError on cancel.
DuplicateResult find_duplicates(const PointCloud& cloud, const DuplicateParams& params = {}, const KdTree* tree = nullptr,
                                const ProgressCallback& progress = {});

/// The kept points of `found` with their attributes merged over each group: position and
/// scalar fields (labels, intensities) of the kept point; colours averaged; normals averaged
/// after turning each to the kept point's side, then normalised (unit length). O(N).
/// Throws UsageError when `found` does not belong to a cloud of this size.
PointCloud merge_duplicates(const PointCloud& cloud, const DuplicateResult& found);

/// find_duplicates then merge_duplicates, replacing `cloud`.
DuplicateResult remove_duplicates(PointCloud& cloud, const DuplicateParams& params = {}, const KdTree* tree = nullptr,
                                  const ProgressCallback& progress = {});

}  // namespace pointsurf
