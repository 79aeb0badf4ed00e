// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Meshes known by construction (cube, icosphere, plane grid, random soups) and brute-force
// oracles that check evaluate/ itself.
#include <cstddef>
#include <cstdint>

#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf::test {
/// Surface of the cube [-half, half]^3, each side an n x n grid of squares split in two,
/// vertices shared along the cube's edges (one closed mesh), faces counter-clockwise from outside.
TriangleMesh grid_cube(int n, double half = 1.0);

/// The cube [c - h, c + h]^3: 8 vertices, 12 triangles, counter-clockwise seen from outside.
TriangleMesh cube_mesh(double half = 1.0, const Vector3d& center = Vector3d::Zero());
/// The cube without its top (+z) face: an open box, one boundary loop of length 8 h.
TriangleMesh open_box_mesh(double half = 1.0, const Vector3d& center = Vector3d::Zero());
/// An icosahedron subdivided `levels` times, vertices on the sphere, faces outward.
TriangleMesh icosphere_mesh(int levels, double radius = 1.0, const Vector3d& center = Vector3d::Zero());
/// The square [-h, h]^2 at z = center.z, n x n quads split in two, normals +z.
TriangleMesh grid_mesh(int n, double half = 1.0, const Vector3d& center = Vector3d::Zero());
/// `count` random triangles in the unit cube (a soup: no shared vertices), seeded.
TriangleMesh random_soup(std::size_t count, std::uint64_t seed = 5);
/// `a` and `b` in one mesh (b's indices shifted).
TriangleMesh join_meshes(const TriangleMesh& a, const TriangleMesh& b);

/// Brute-force squared distance from p to the mesh: every triangle, by projection onto its
/// plane when the projection falls inside and by its three edges otherwise.
double brute_force_squared_distance(const Vector3d& p, const TriangleMesh& mesh);

/// Signed distance to the box [c - h, c + h]^3, analytic (negative inside).
double box_signed_distance(const Vector3d& p, double half, const Vector3d& center = Vector3d::Zero());

}  // namespace pointsurf::test
