// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// M3C2 (Lague, Brodu, Leroux 2013, "Accurate 3D comparison of complex topography with terrestrial
// laser scanner"): the distance between two clouds measured along the local normal of the first,
// in a cylinder around each core point, with a 95% level of detection.
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf {

class KdTree;

struct M3c2Params {
  double normal_scale = 0.0;                  // D: diameter of the neighbourhood of cloud 1 that gives a
                                              // core point's normal, cloud units; 0: normal_scale_in_spacings
  double normal_scale_in_spacings = 10.0;     // x the mean spacing of cloud 1
  double projection_scale = 0.0;              // d: diameter of the cylinder, cloud units; 0: below
  double projection_scale_in_spacings = 6.0;  // x the mean spacing of cloud 1
  double max_depth = 0.0;                     // half-length of the cylinder, cloud units; 0: below
  double max_depth_in_spacings = 30.0;        // x the mean spacing of cloud 1
  double registration_error = 0.0;            // added to the level of detection, cloud units
  std::size_t min_points = 3;                 // points each cloud needs in a cylinder (>= 2)
};

struct M3c2Result {
  std::vector<double> distance;        // per core point, cloud units: mean position of cloud 2 minus that of
                                       // cloud 1 along the normal (NaN: too few points)
  std::vector<double> lod95;           // 1.96 sqrt(s1^2/n1 + s2^2/n2) + registration_error (NaN likewise)
  std::vector<char> significant;       // |distance| > lod95
  std::vector<Vector3d> normals;       // unit; towards cloud 1's normals where it has them, else +z
  std::vector<std::uint32_t> count1, count2;  // points in each cylinder
  std::size_t valid = 0;               // core points with a distance
  std::size_t significant_count = 0;
  double normal_scale = 0.0, projection_scale = 0.0, max_depth = 0.0;  // the values used
};

/// M3C2 distances from `cloud1` to `cloud2` at `core_points` (empty: every point of cloud 1).
/// Trees over the clouds may be passed to be reused. Differences are taken about each core point,
/// so 1e6 m coordinates lose nothing. Throws InputError for an empty cloud and UsageError for
/// negative scales or min_points < 2. Parallel; thread-safe.
M3c2Result m3c2_distances(const PointCloud& cloud1, const PointCloud& cloud2, std::span<const Vector3d> core_points = {},
                          const M3c2Params& params = {}, const KdTree* tree1 = nullptr, const KdTree* tree2 = nullptr);

}  // namespace pointsurf
