// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Analytic shapes with known normals, sampled with seeded RNGs, for tests.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

/// n points uniformly on a sphere (area-uniform), exact outward normals.
PointCloud sample_sphere(std::size_t n, double radius = 1.0, const Vector3d& center = Vector3d::Zero(), std::uint64_t seed = 1);
/// n points uniformly on the square [-half, half]^2 in the plane z = 0, normals +z.
PointCloud sample_plane(std::size_t n, double half = 1.0, std::uint64_t seed = 1);
/// n points area-uniformly on the surface of the axis-aligned cube [-half, half]^3, outward normals.
PointCloud sample_cube(std::size_t n, double half = 1.0, std::uint64_t seed = 1);
/// n points on a torus (major R, minor r) around z, outward normals.
PointCloud sample_torus(std::size_t n, double major = 1.0, double minor = 0.3, std::uint64_t seed = 1);
/// Adds Gaussian noise of standard deviation sigma to the positions (seeded).
void add_noise(PointCloud& cloud, double sigma, std::uint64_t seed = 7);

/// Path of a file shipped in data/ (the test fails if it is missing).
std::filesystem::path data_path(const std::string& name);
/// Path of a file made for the tests in tests/data/ (the test fails if it is missing).
std::filesystem::path test_data_path(const std::string& name);
/// A fresh empty directory under the system temp dir for one test.
std::filesystem::path temp_dir(const std::string& name);

/// n uniform points in [0, 1]^3 + offset, then `duplicates` exact copies of earlier points
/// (seeded): neighbour searches against brute force.
std::vector<Vector3d> random_box_points(std::size_t n, std::size_t duplicates, const Vector3d& offset = Vector3d::Zero(),
                                        std::uint64_t seed = 3);
/// The integer lattice side^3 scaled by h, plus offset: many exactly equal distances (ties).
std::vector<Vector3d> lattice_points(int side, double h = 1.0, const Vector3d& offset = Vector3d::Zero());

}  // namespace pointsurf::test
