// SPDX-License-Identifier: GPL-3.0-or-later
// Thin wrappers over evaluate/ (surface_distance.h), kept for the tests that use these names.
#include "support/distances.h"

#include <cmath>

#include "pointsurf/evaluate/surface_distance.h"

namespace pointsurf::test {

std::vector<double> nearest_distances(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to) {
  if (to.empty()) return std::vector<double>(from.size(), INFINITY);
  return nearest_surface_distances(from, SurfaceView{to, {}});
}

SetDistances set_distances(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b) {
  SetDistances d;
  if (a.empty() || b.empty()) return d;
  const SurfaceDistanceResult r = surface_distance(SurfaceView{a, {}}, SurfaceView{b, {}});
  d.chamfer = r.chamfer;
  d.hausdorff = r.hausdorff;
  d.rms_ab = r.a_to_b.rms;
  return d;
}

std::vector<Vector3d> sample_mesh_surface(const std::vector<Vector3d>& vertices, const std::vector<Eigen::Vector3i>& triangles,
                                          std::size_t n, std::uint64_t seed) {
  return pointsurf::sample_mesh_surface(vertices, triangles, n, seed);
}

}  // namespace pointsurf::test
