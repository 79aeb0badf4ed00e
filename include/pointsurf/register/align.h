// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Global (initial) alignment of two scans from descriptor matches: correspondences by mutual
// nearest neighbour in descriptor space, then RANSAC over triples of correspondences pruned by
// edge-length and normal-angle checks before any model is scored, stopped when the chance of
// having missed the best model falls below 1 - confidence (or at the iteration cap).
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/register/features.h"
#include "pointsurf/register/result.h"

namespace pointsurf {

struct AlignParams {
  Length max_distance = Length::spacings(1.5);  // a matched pair is an inlier within this
                                         // distance after the transform, cloud units or the
                                         // source's mean spacings, > 0
  bool mutual = true;                    // keep only mutual nearest neighbours in descriptor space
  double edge_length_ratio = 0.9;        // pruning: the two triangles' edge lengths agree within
                                         // this ratio, in (0, 1]
  double max_normal_deg = 45.0;          // pruning: matched normals agree within this angle after
                                         // the candidate rotation, degrees; 180 disables
  std::size_t max_iterations = 100000;   // RANSAC trials at most
  double confidence = 0.999;             // stop when a better model would have been found with
                                         // this probability, in (0, 1)
  std::uint64_t seed = 42;               // random seed
  /// Key, unit, range and doc of each field (core/fields.h): ransac_distance, ransac_iterations,
  /// confidence, seed (the keys of the register stages).
  static const FieldTable<AlignParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Index pairs (source, target) of matched descriptors; invalid descriptors never match.
std::vector<std::pair<std::uint32_t, std::uint32_t>> match_descriptors(const Descriptors& source, const Descriptors& target,
                                                                       bool mutual);

/// The transform taking `source` onto `target` from their descriptors (computed on these same
/// clouds, with normals). `target_tree` is built over the target's positions and is reused for
/// scoring. Works in a frame centred on the target's centroid, so 1e6 m coordinates lose nothing.
/// Each trial draws 3 matches (seeded per trial), rejects them by edge lengths, then fits them
/// (Kabsch) and rejects the fit by the three distances and normal angles; a survivor is counted
/// against all matches, and those with at least half the best count are scored by the fitness
/// of a fixed sample of 1000 source points (as Open3D scores every survivor). The winner is
/// refined on its inlier matches and by point-to-plane steps on that sample (local
/// optimisation, Chum et al. 2003), keeping the step of least truncated squared distance.
/// Trials run in fixed batches of 512, so the answer for a seed does not depend on the thread
/// count. converged = true when the confidence was reached before max_iterations (computed from
/// the winner's share of inlier matches); otherwise the best pose found is still returned, with
/// converged = false and the trials it would have needed in `message`. Too few points (< 3) or
/// matches (< 3) give converged = false; bad parameters or mismatched inputs throw UsageError.
/// Thread-safe; parallel (oneTBB).
RegistrationResult align_global(const PointCloud& source, const Descriptors& source_features, const PointCloud& target,
                                const Descriptors& target_features, const KdTree& target_tree, const AlignParams& params,
                                const ProgressCallback& progress = {});

}  // namespace pointsurf
