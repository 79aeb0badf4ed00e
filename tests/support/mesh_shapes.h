// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Triangle meshes whose faces are known by construction, for tests over meshes.
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::test {

/// Icosahedron subdivided `levels` times (20 x 4^levels faces), vertices on the sphere, faces
/// counter-clockwise seen from outside.
TriangleMesh icosphere(int levels, double radius = 1.0, const Vector3d& center = Vector3d::Zero());
/// Surface of the cube [-half, half]^3, each side an n x n grid of squares split in two,
/// vertices shared along the cube's edges (one closed mesh), faces counter-clockwise from outside.
TriangleMesh grid_cube(int n, double half = 1.0);

}  // namespace pointsurf::test
