// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Helpers for the cleaning tests: injected outliers with known indices, exact distances to
// the analytic shapes of shapes.h, and detection scores.
#include <cstdint>
#include <functional>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

/// Appends `count` "drift" points: copies of random points of `cloud` (which needs normals)
/// pushed along their normal by a height uniform in [min_height, max_height] (cloud units).
/// Returns the indices of the appended points. Seeded.
std::vector<std::uint32_t> add_drift_outliers(PointCloud& cloud, std::size_t count, double min_height, double max_height,
                                              std::uint64_t seed = 11);

/// Appends `count` points uniform in the cloud's bounding box grown by `margin` on each side,
/// keeping only those with `distance_to_surface(p) >= min_distance`. Returns their indices.
std::vector<std::uint32_t> add_scattered_outliers(PointCloud& cloud, std::size_t count, double margin, double min_distance,
                                                  const std::function<double(const Vector3d&)>& distance_to_surface,
                                                  std::uint64_t seed = 13);

/// Distance from p to the sphere |x - center| = radius.
double distance_to_sphere(const Vector3d& p, double radius = 1.0, const Vector3d& center = Vector3d::Zero());
/// Distance from p to the surface of the cube [-half, half]^3.
double distance_to_cube(const Vector3d& p, double half = 1.0);
/// Distance from p to the nearest of the 12 edges of the cube [-half, half]^3.
double distance_to_cube_edge(const Vector3d& p, double half = 1.0);

/// RMS of `distance(p)` over the points (all when `select` is empty, else those with select[i]).
double rms_distance(const std::vector<Vector3d>& points, const std::function<double(const Vector3d&)>& distance,
                    const std::vector<bool>& select = {});

struct Detection {
  double precision = 0.0;  // removed points that are true outliers / removed (1 when none removed)
  double recall = 0.0;     // true outliers removed / true outliers (1 when there are none)
};
/// Scores an outlier filter that kept `kept` (ascending) of `n` points, given the true outliers.
Detection score_removal(const std::vector<std::uint32_t>& kept, std::size_t n, const std::vector<std::uint32_t>& outliers);

}  // namespace pointsurf::test
