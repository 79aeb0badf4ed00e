// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Comparing reconstructed meshes with each other and with analytic surfaces (the cocone and Crust
// tests).
#include <array>
#include <functional>
#include <set>
#include <utility>
#include <vector>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::test {

/// The mesh's triangles as a set, each rotated so that its smallest index comes first (so the
/// orientation is kept); with `to_original`, vertex v is renumbered to_original[v] first.
std::set<std::array<int, 3>> oriented_triangle_set(const TriangleMesh& mesh, const std::vector<int>& to_original = {});

/// Largest distance from the mesh surface (100k area samples) to the true surface (`distance`),
/// and from the true surface (dense samples `truth`) to the mesh surface samples.
std::pair<double, double> hausdorff_to_surface(const TriangleMesh& mesh, const std::vector<Vector3d>& truth,
                                               const std::function<double(const Vector3d&)>& distance);

/// Triangles whose normal points towards `centre` (face normal . (centroid - centre) < 0).
std::size_t inward_faces(const TriangleMesh& mesh, const Vector3d& centre);

}  // namespace pointsurf::test
