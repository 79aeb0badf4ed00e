// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/shapes.h"

#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>
#include <unistd.h>

namespace pointsurf::test {

PointCloud sample_sphere(std::size_t n, double radius, const Vector3d& center, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud cloud;
  cloud.positions.reserve(n);
  cloud.normals.reserve(n);
  while (cloud.positions.size() < n) {
    Vector3d v(g(rng), g(rng), g(rng));
    const double len = v.norm();
    if (len < 1e-12) continue;
    v /= len;
    cloud.positions.push_back(center + radius * v);
    cloud.normals.push_back(v);
  }
  return cloud;
}

PointCloud sample_plane(std::size_t n, double half, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng);  // sequenced: the order of RNG draws is fixed
    const double y = u(rng);
    cloud.positions.emplace_back(x, y, 0.0);
    cloud.normals.emplace_back(0.0, 0.0, 1.0);
  }
  return cloud;
}

PointCloud sample_cube(std::size_t n, double half, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  std::uniform_int_distribution<int> face(0, 5);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const int f = face(rng);
    const int axis = f / 2;
    const double sign = (f % 2 == 0) ? 1.0 : -1.0;
    const double a = u(rng);
    const double b = u(rng);
    Vector3d p, nrm = Vector3d::Zero();
    p[axis] = sign * half;
    p[(axis + 1) % 3] = a;
    p[(axis + 2) % 3] = b;
    nrm[axis] = sign;
    cloud.positions.push_back(p);
    cloud.normals.push_back(nrm);
  }
  return cloud;
}

PointCloud sample_torus(std::size_t n, double major, double minor, std::uint64_t seed) {
  // Rejection sampling on the tube angle gives area-uniform samples (area element ~ R + r cos v).
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  PointCloud cloud;
  while (cloud.positions.size() < n) {
    const double a = 2.0 * std::numbers::pi * u01(rng);
    const double v = 2.0 * std::numbers::pi * u01(rng);
    const double w = u01(rng);
    if (w * (major + minor) > major + minor * std::cos(v)) continue;
    const Vector3d radial(std::cos(a), std::sin(a), 0.0);
    const Vector3d nrm = std::cos(v) * radial + std::sin(v) * Vector3d::UnitZ();
    cloud.positions.push_back(major * radial + minor * nrm);
    cloud.normals.push_back(nrm);
  }
  return cloud;
}

void add_noise(PointCloud& cloud, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (Vector3d& p : cloud.positions) {
    const double dx = g(rng), dy = g(rng), dz = g(rng);
    p += Vector3d(dx, dy, dz);
  }
}

std::filesystem::path data_path(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(POINTSURF_DATA_DIR) / name;
  EXPECT_TRUE(std::filesystem::exists(p)) << "test data missing: " << p;
  return p;
}

std::filesystem::path test_data_path(const std::string& name) {
  const std::filesystem::path p = std::filesystem::path(POINTSURF_DATA_DIR).parent_path() / "tests" / "data" / name;
  EXPECT_TRUE(std::filesystem::exists(p)) << "test data missing: " << p;
  return p;
}

std::filesystem::path temp_dir(const std::string& name) {
  const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                  ("pointsurf_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

std::vector<Vector3d> random_box_points(std::size_t n, std::size_t duplicates, const Vector3d& offset, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Vector3d> p;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    p.push_back(offset + Vector3d(x, y, z));
  }
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  for (std::size_t i = 0; i < duplicates; ++i) p.push_back(p[pick(rng)]);
  return p;
}

std::vector<Vector3d> lattice_points(int side, double h, const Vector3d& offset) {
  std::vector<Vector3d> p;
  for (int z = 0; z < side; ++z)
    for (int y = 0; y < side; ++y)
      for (int x = 0; x < side; ++x) p.push_back(offset + h * Vector3d(x, y, z));
  return p;
}

}  // namespace pointsurf::test
