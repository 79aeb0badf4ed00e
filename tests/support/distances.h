// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Distances between point sets over the KdTree, for quality checks in tests.
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

/// For each point of `from`, the distance to the nearest point of `to` (N values).
std::vector<double> nearest_distances(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to);

struct SetDistances {
  double chamfer = 0.0;    // mean of the two one-sided mean distances (smaller is better)
  double hausdorff = 0.0;  // max of the two one-sided maximum distances (smaller is better)
  double rms_ab = 0.0;     // RMS of a -> b nearest distances
};
/// Symmetric Chamfer and Hausdorff distances between two point sets.
SetDistances set_distances(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b);

/// Points sampled area-uniformly on the triangles of a mesh (seeded), for mesh-to-surface distances.
std::vector<Vector3d> sample_mesh_surface(const std::vector<Vector3d>& vertices, const std::vector<Eigen::Vector3i>& triangles,
                                          std::size_t n, std::uint64_t seed = 3);

}  // namespace pointsurf::test
