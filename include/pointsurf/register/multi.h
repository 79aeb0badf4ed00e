// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Registration of several scans into one frame (the first scan's): each scan registered to the
// first or to the one before it (a chain), then every pair found to overlap under those poses
// registered too, and all the poses refined together on a pose graph (pose_graph.h), which
// spreads the error a chain accumulates and closes loops. The scans are then merged into one
// cloud with an integer field "scan".
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/register/pose_graph.h"
#include "pointsurf/register/register_pair.h"

namespace pointsurf {

enum class MultiMode : std::uint8_t {
  First = 0,  // scan i registered to scan 0: no drift, but far scans may not overlap the first
  Chain = 1,  // scan i registered to scan i - 1: neighbours overlap most; errors add up
};
/// "first", "chain".
const EnumNames<MultiMode>& multi_mode_names();
/// "first", "chain" (multi_mode_names()).
const char* multi_mode_name(MultiMode mode) noexcept;

struct RegisterScansParams {
  RegisterPairParams pair;             // each pairwise registration
  MultiMode mode = MultiMode::Chain;
  bool refine = true;                  // global refinement over all overlapping pairs
  double min_overlap = 0.2;            // a further pair (i, j) joins the refinement when this
                                       // share of i's downsample lies within the fine ICP distance
                                       // of j under the initial poses, in (0, 1]
  Length prune = Length::spacings(0.75);  // an overlap pair (not one of the first pass) that
                                       // still disagrees with the refined poses by more than this
                                       // (RMS displacement of its points, cloud units or the
                                       // largest mean spacing) is taken as a wrong registration
                                       // and dropped, > 0
  std::size_t graph_iterations = 50;   // Gauss-Newton iterations of the pose graph at most
  /// Key, unit, range and doc of each field (core/fields.h), those of pair included.
  static const FieldTable<RegisterScansParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// One pairwise registration used by the poses.
struct ScanLink {
  std::size_t source = 0, target = 0;  // scan indices: `result.transform` maps source onto target
  RegistrationResult result;
  bool initial = false;                // from the first pass (first or chain), else an overlap
                                       // found afterwards
  bool pruned = false;                 // dropped by the pose graph (its residual stayed large)

  /// The reported members (core/results.h), under a prefix naming the two scans.
  static const ResultTable<ScanLink>& results();
};

struct RegisterScansResult {
  std::vector<RigidTransform> poses;          // pose i maps scan i into scan 0's frame (pose 0
                                              // is the identity)
  std::vector<RigidTransform> initial_poses;  // the same from the first pass alone
  std::vector<ScanLink> links;                // every pairwise registration, first pass first
  std::vector<std::uint8_t> normals_estimated;  // per scan: 1 when it had no normals
  PoseGraphResult graph;                      // the refinement (empty when refine is off)
  double spacing = 0.0;                       // the largest mean spacing of the scans
  double seconds_prepare = 0.0;               // normals, downsamples, descriptors
  double seconds_initial = 0.0;               // the first pass
  double seconds_overlaps = 0.0;              // finding and registering the other overlapping pairs
  double seconds_graph = 0.0;

  /// The reported members (core/results.h): the spacing and the times (the poses, links and
  /// graph are reported through their own tables).
  static const ResultTable<RegisterScansResult>& results();
};

/// The poses of `scans` (at least 2) in the first scan's frame. Throws InputError when a scan
/// has fewer than kMinRegistrationPoints points, ComputeError naming the scan when the first
/// pass cannot place it (its registration found no overlap: fitness below
/// params.pair.min_fitness), UsageError for bad parameters, CancelledError when `progress`
/// returns false. Bounded: n - 1 registrations, at most n (n - 1) / 2 overlap checks and
/// registrations, and the pose graph's bounded solves. Thread-safe.
RegisterScansResult register_scans(const std::vector<PointCloud>& scans, const RegisterScansParams& params = {},
                                   const ProgressCallback& progress = {});

/// The scans moved by their poses and appended in order, with a field "scan" (UInt16, or UInt32
/// beyond 65536 scans) holding each point's scan index; attributes present in only some scans
/// are zero-filled there. Throws UsageError when the counts differ.
PointCloud merge_scans(const std::vector<PointCloud>& scans, const std::vector<RigidTransform>& poses);

}  // namespace pointsurf
