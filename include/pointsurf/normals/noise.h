// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// How noisy a scan is against its own sampling: the thickness of each neighbourhood (RMS distance
// to its best-fit plane) in local spacings. Interpolating reconstructions need it well below one
// spacing; the reconstruct stage warns above kNoisyInSpacings.
#include <cstddef>
#include <cstdint>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct NoiseEstimate {
  double median_in_spacings = 0.0;  // median over the sampled points of sqrt(l0) / local spacing,
                                    // l0 the smallest eigenvalue of the k-neighbourhood covariance,
                                    // the local spacing the mean distance to the 3 nearest others
  double p90_in_spacings = 0.0;     // its 90th percentile
  std::size_t samples = 0;          // points sampled (those with a positive local spacing)
};

/// Above this median a surface through the points comes out shredded (measured: CGAL's noisy
/// sphere_20k.xyz 0.62; clean scans 0.01 (radar.xyz), 0.09 (kitten, b9), 0.13 (armadillo
/// samples), 0.28 (building.ply facade)).
constexpr double kNoisyInSpacings = 0.4;

/// Estimates the noise of `cloud` from `max_samples` points drawn with `seed` (all points when the
/// cloud is smaller), each with its `k` nearest neighbours from `tree` (built over
/// cloud.positions). A plane sampled exactly gives 0; uniform noise of amplitude a gives about
/// a / sqrt(3) / spacing. Curvature adds a little: r = 50 spacings gives about 0.01.
/// Parallel (oneTBB), deterministic. Throws UsageError for k < 4.
NoiseEstimate estimate_noise(const PointCloud& cloud, const KdTree& tree, std::size_t k = 16, std::size_t max_samples = 2000,
                             std::uint64_t seed = 42);

}  // namespace pointsurf
