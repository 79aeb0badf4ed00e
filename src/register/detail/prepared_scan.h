// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A scan made ready for registration once, however many pairs it takes part in: normals, the
// kd-tree and spacing of every point, the voxel downsample with its tree and descriptors.
#include <chrono>
#include <memory>
#include <optional>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/register/features.h"
#include "pointsurf/register/register_pair.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {

struct PreparedScan {
  PointCloud cloud;                    // every point, with normals
  std::unique_ptr<KdTree> tree;
  double spacing = 0.0;                // mean spacing of `cloud`
  bool normals_estimated = false;
  std::optional<PointCloud> sampled;   // the voxel downsample (none when the cell is 0)
  std::unique_ptr<KdTree> sampled_tree;
  Descriptors features;                // of the downsample (empty when not needed)
  const PointCloud& coarse() const { return sampled ? *sampled : cloud; }
  const KdTree& coarse_tree() const { return sampled ? *sampled_tree : *tree; }
};

/// Lengths resolved once for a set of scans, so that every pair uses the same ones.
struct PairLengths {
  double spacing = 0.0;        // the largest mean spacing of the scans
  double voxel = 0.0;          // downsample cell (0: none)
  double coarse_spacing = 0.0; // what the descriptor radius and RANSAC distance count
  DescriptorParams features;      // radius resolved
  AlignParams align;           // max_distance resolved
  IcpParams coarse_icp, fine_icp;  // max_distance resolved
};

/// Normals (estimated when missing), kd-tree and spacing. InputError for too few points or
/// points that all coincide; `what` names the cloud in messages ("source", "scan 3").
PreparedScan prepare_points(const PointCloud& cloud, const RegisterPairParams& params, const std::string& what, const ProgressCallback& progress);
PairLengths resolve_lengths(const RegisterPairParams& params, double largest_spacing);
/// The downsample and its tree (nothing when lengths.voxel is 0).
void prepare_coarse(PreparedScan& scan, const PairLengths& lengths);
/// Global alignment (unless params.global is off), coarse ICP and fine ICP of prepared scans.
RegisterPairResult register_prepared(const PreparedScan& source, const PreparedScan& target, const RegisterPairParams& params, const PairLengths& lengths,
                             const ProgressCallback& progress);

/// The part [begin, end] of a whole progress range (empty when `whole` is).
inline ProgressCallback progress_part(const ProgressCallback& whole, double begin, double end) {
  if (!whole) return {};
  return [whole, begin, end](double f) { return whole(begin + (end - begin) * f); };
}

inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace pointsurf::detail
