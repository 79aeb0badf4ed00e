// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/reconstruct_surface.h"

#include <algorithm>
#include <cmath>

#include "pointsurf/evaluate/surface_distance.h"

namespace pointsurf::test {

std::vector<Vector3d> sample_triangles(const TriangleMesh& mesh, std::size_t n, std::uint64_t seed) {
  return sample_mesh_surface(mesh, n, seed);
}

double max_nearest_distance(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to) {
  if (from.empty()) return 0.0;
  if (to.empty()) return INFINITY;
  double worst = 0.0;
  for (const double d : nearest_surface_distances(from, SurfaceView{to, {}})) worst = std::max(worst, d);
  return worst;
}

}  // namespace pointsurf::test
