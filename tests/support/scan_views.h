// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Partial scans of a known object (the kitten of data/) in frames of their own, with known
// poses: the registration tests' answers known by construction.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/rigid_transform.h"

namespace pointsurf::test {

inline constexpr double kKittenSpacing = 0.0172;  // mean spacing of data/kitten.xyz

/// data/kitten.xyz: 5210 points with normals, about 1 unit tall along y. Read once.
const PointCloud& kitten();
/// The mean of a cloud's positions.
Eigen::Vector3d centroid(const PointCloud& cloud);

struct ScanViews {
  std::vector<PointCloud> clouds;     // each in its own frame, with normals
  std::vector<RigidTransform> truth;  // pose k: scan k's frame -> scan 0's frame (pose 0: identity)
};

/// n scans of the kitten from viewpoints around its vertical (y) axis: each sees the points
/// facing it, a seeded 80 % of them, moved by Gaussian noise of `sigma_in_spacings` kitten
/// spacings, and sits in a frame of its own (a seeded rotation of 11-46 degrees and a shift of
/// about 0.3). Views 360/n degrees apart (or `step_deg` when > 0): neighbours overlap by about
/// half, and around the full turn the last overlaps the first, closing a loop.
ScanViews scan_views(std::size_t n, double sigma_in_spacings, std::uint64_t seed, double step_deg = 0.0);

}  // namespace pointsurf::test
