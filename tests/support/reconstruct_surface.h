// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Surface samples and distances for the reconstruction tests.
#include <cstdint>
#include <vector>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::test {

/// n points area-uniformly on the triangles of `mesh` (seeded); empty for a mesh without area.
std::vector<Vector3d> sample_triangles(const TriangleMesh& mesh, std::size_t n, std::uint64_t seed = 3);

/// Largest distance from a point of `from` to its nearest point of `to` (one-sided Hausdorff
/// between point sets); infinity when `to` is empty and `from` is not.
double max_nearest_distance(const std::vector<Vector3d>& from, const std::vector<Vector3d>& to);

}  // namespace pointsurf::test
