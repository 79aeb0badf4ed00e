// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/primitive_scene.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>

namespace pointsurf::test {

PrimitiveScene make_primitive_scene(double per_unit_area, double sigma, std::uint64_t seed) {
  PrimitiveScene scene;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, sigma);
  std::vector<double>& truth = scene.cloud.fields.add("truth", 0).values;
  auto add = [&](const Vector3d& p, const Vector3d& n, int label) {
    scene.cloud.positions.push_back(p + noise(rng) * n);
    scene.cloud.normals.push_back(n);
    truth.push_back(label);
  };
  auto count = [&](double area) { return std::size_t(area * per_unit_area); };
  const auto frame = [](const Vector3d& a) {
    const Vector3d x = (std::abs(a.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).cross(a).normalized();
    return std::pair<Vector3d, Vector3d>{x, a.cross(x)};
  };
  // 0: ground, 1: wall.
  Primitive ground{PrimitiveType::Plane, Vector3d(0, 0, 0), Vector3d::UnitZ()};
  for (std::size_t i = 0, n = count(100.0); i < n; ++i) add(Vector3d(10 * u(rng) - 5, 10 * u(rng) - 5, 0.0), Vector3d::UnitZ(), 0);
  Primitive wall{PrimitiveType::Plane, Vector3d(0, 5, 2), Vector3d::UnitY()};
  for (std::size_t i = 0, n = count(40.0); i < n; ++i) add(Vector3d(10 * u(rng) - 5, 5.0, 0.3 + 4 * u(rng)), Vector3d::UnitY(), 1);
  // 2: sphere.
  Primitive sphere{PrimitiveType::Sphere, Vector3d(2.2, -2.0, 2.0), Vector3d::UnitZ(), 1.2};
  for (std::size_t i = 0, n = count(4 * M_PI * 1.44); i < n; ++i) {
    const double z = 2 * u(rng) - 1, phi = 2 * M_PI * u(rng), s = std::sqrt(1 - z * z);
    const Vector3d d(s * std::cos(phi), s * std::sin(phi), z);
    add(sphere.point + sphere.radius * d, d, 2);
  }
  // 3: cylinder, tilted.
  Primitive cylinder{PrimitiveType::Cylinder, Vector3d(-2.2, -2.0, 2.2), Vector3d(0.3, 0.2, 1.0).normalized(), 0.8};
  {
    const auto [x, y] = frame(cylinder.axis);
    for (std::size_t i = 0, n = count(2 * M_PI * 0.8 * 2.4); i < n; ++i) {
      const double phi = 2 * M_PI * u(rng), h = 2.4 * u(rng) - 1.2;
      const Vector3d d = std::cos(phi) * x + std::sin(phi) * y;
      add(cylinder.point + h * cylinder.axis + cylinder.radius * d, d, 3);
    }
  }
  // 4: cone, apex up, half angle 30 degrees, from 0.6 to 3.0 below the apex.
  Primitive cone{PrimitiveType::Cone, Vector3d(1.5, 2.0, 3.6), -Vector3d::UnitZ(), 0.0, 30.0};
  {
    const auto [x, y] = frame(cone.axis);
    const double t = std::tan(30.0 * M_PI / 180.0), h1 = 0.6, h2 = 3.0;
    const double area = M_PI * t * (h2 * h2 - h1 * h1) / std::cos(30.0 * M_PI / 180.0);
    for (std::size_t i = 0, n = count(area); i < n; ++i) {
      const double h = std::sqrt(h1 * h1 + u(rng) * (h2 * h2 - h1 * h1)), phi = 2 * M_PI * u(rng);
      const Vector3d d = std::cos(phi) * x + std::sin(phi) * y;
      const Vector3d normal = (std::cos(30.0 * M_PI / 180.0) * d - std::sin(30.0 * M_PI / 180.0) * cone.axis).normalized();
      add(cone.point + h * cone.axis + h * t * d, normal, 4);
    }
  }
  scene.truth = {ground, wall, sphere, cylinder, cone};
  return scene;
}

}  // namespace pointsurf::test
