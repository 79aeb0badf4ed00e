// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/terrain_scene.h"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

namespace pointsurf::test {
namespace {

constexpr double kTileSide = 100.0;      // m
constexpr double kScannerHeight = 600.0; // m above z = 0
constexpr double kNoHit = std::numeric_limits<double>::infinity();

struct Hit {
  double t = kNoHit;
  Vector3d normal = Vector3d::UnitZ();
  double cls = kLasGround;
};

struct Ray {
  Vector3d origin, direction;
  Vector3d at(double t) const { return origin + t * direction; }
};

struct Ground {
  double phase_x = 0.0, phase_y = 0.0;
  double height(double x, double y) const { return 0.03 * x + 2.0 * std::sin(x / 15.0 + phase_x) * std::cos(y / 20.0 + phase_y); }
  Vector3d normal(double x, double y) const {
    const double gx = 0.03 + 2.0 / 15.0 * std::cos(x / 15.0 + phase_x) * std::cos(y / 20.0 + phase_y);
    const double gy = -2.0 / 20.0 * std::sin(x / 15.0 + phase_x) * std::sin(y / 20.0 + phase_y);
    return Vector3d(-gx, -gy, 1.0).normalized();
  }
};

struct Box {
  Vector3d min, max;
  double cls;
};

struct Tree {
  Vector3d crown;  // centre of the crown
  double radius, trunk_bottom;
};

// The first entry of the ray into the box (slab method), with the entered face's normal.
void hit_box(const Ray& ray, const Box& box, Hit& best) {
  double enter = 0.0, leave = kNoHit;
  int axis = -1;
  double sign = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = ray.direction[a];
    if (std::abs(d) < 1e-15) {
      if (ray.origin[a] < box.min[a] || ray.origin[a] > box.max[a]) return;
      continue;
    }
    double t0 = (box.min[a] - ray.origin[a]) / d, t1 = (box.max[a] - ray.origin[a]) / d;
    double s = -1.0;
    if (t0 > t1) {
      std::swap(t0, t1);
      s = 1.0;
    }
    if (t0 > enter) {
      enter = t0;
      axis = a;
      sign = s;
    }
    leave = std::min(leave, t1);
  }
  if (axis < 0 || enter > leave || enter >= best.t) return;
  best.t = enter;
  best.normal = Vector3d::Zero();
  best.normal[axis] = sign;
  best.cls = box.cls;
}

// Foliage: the return comes from `depth` (0..1) of the way to the middle of the chord.
void hit_crown(const Ray& ray, const Tree& tree, double depth, Hit& best) {
  const Vector3d oc = ray.origin - tree.crown;
  const double b = oc.dot(ray.direction), c = oc.squaredNorm() - tree.radius * tree.radius;
  const double disc = b * b - c;
  if (disc < 0.0) return;
  const double t = -b - (1.0 - depth) * std::sqrt(disc);
  if (t <= 0.0 || t >= best.t) return;
  best.t = t;
  best.normal = (ray.at(-b - std::sqrt(disc)) - tree.crown).normalized();
  best.cls = kLasVegetation;
}

void hit_trunk(const Ray& ray, const Tree& tree, Hit& best) {
  constexpr double kTrunkRadius = 0.3;
  const Eigen::Vector2d o(ray.origin.x() - tree.crown.x(), ray.origin.y() - tree.crown.y());
  const Eigen::Vector2d d(ray.direction.x(), ray.direction.y());
  const double a = d.squaredNorm();
  if (a < 1e-15) return;
  const double b = o.dot(d), c = o.squaredNorm() - kTrunkRadius * kTrunkRadius;
  const double disc = b * b - a * c;
  if (disc < 0.0) return;
  const double t = (-b - std::sqrt(disc)) / a;
  if (t <= 0.0 || t >= best.t) return;
  const Vector3d p = ray.at(t);
  if (p.z() < tree.trunk_bottom || p.z() > tree.crown.z()) return;
  best.t = t;
  best.normal = Vector3d(p.x() - tree.crown.x(), p.y() - tree.crown.y(), 0.0).normalized();
  best.cls = kLasVegetation;
}

// The ground is below z = 40 everywhere: march from there in 0.25 m steps, then bisect.
void hit_ground(const Ray& ray, const Ground& ground, Hit& best) {
  double t = (ray.origin.z() - 40.0) / -ray.direction.z();
  auto above = [&](double s) {
    const Vector3d p = ray.at(s);
    return p.z() - ground.height(p.x(), p.y());
  };
  double prev = t;
  while (above(t) > 0.0) {
    prev = t;
    t += 0.25;
    if (t >= best.t) return;
  }
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (prev + t);
    (above(mid) > 0.0 ? prev : t) = mid;
  }
  if (t >= best.t) return;
  const Vector3d p = ray.at(t);
  best.t = t;
  best.normal = ground.normal(p.x(), p.y());
  best.cls = kLasGround;
}

}  // namespace

TerrainTile sample_terrain_tile(std::size_t n, std::uint64_t seed, std::size_t trees, double sigma) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto between = [&](double lo, double hi) { return lo + (hi - lo) * u(rng); };
  Ground ground;
  ground.phase_x = between(0.0, 2.0 * std::numbers::pi);
  ground.phase_y = between(0.0, 2.0 * std::numbers::pi);

  // Footprints (x0, y0, x1, y1) placed apart from each other.
  std::vector<Eigen::Vector4d> taken;
  auto place = [&](double w, double d, double margin) {
    for (int attempt = 0;; ++attempt) {
      const double x = between(5.0, kTileSide - 5.0 - w), y = between(5.0, kTileSide - 5.0 - d);
      const Eigen::Vector4d f(x, y, x + w, y + d);
      bool free = true;
      for (const Eigen::Vector4d& g : taken)
        free = free && (f[0] > g[2] + margin || f[2] < g[0] - margin || f[1] > g[3] + margin || f[3] < g[1] - margin);
      if (free || attempt > 1000) {  // a crowded tile: trees may overlap
        taken.push_back(f);
        return f;
      }
    }
  };
  std::vector<Box> boxes;
  const Eigen::Vector4d deck = place(6.0, 40.0, 4.0);  // the bridge, along y
  const double deck_z = ground.height(0.5 * (deck[0] + deck[2]), 0.5 * (deck[1] + deck[3])) + 5.0;
  boxes.push_back({Vector3d(deck[0], deck[1], deck_z), Vector3d(deck[2], deck[3], deck_z + 0.8), kLasBridge});
  for (int b = 0; b < 4; ++b) {
    const Eigen::Vector4d f = place(between(10.0, 18.0), between(10.0, 18.0), 5.0);
    const double base = std::min({ground.height(f[0], f[1]), ground.height(f[2], f[1]), ground.height(f[0], f[3]),
                                  ground.height(f[2], f[3])}) - 1.0;
    const double top = base + 1.0 + between(8.0, 16.0);
    boxes.push_back({Vector3d(f[0], f[1], base), Vector3d(f[2], f[3], top), kLasBuilding});                          // walls
    boxes.push_back({Vector3d(f[0] - 1.0, f[1] - 1.0, top), Vector3d(f[2] + 1.0, f[3] + 1.0, top + 0.4), kLasBuilding});  // roof with eaves
  }
  std::vector<Tree> crowns;
  for (std::size_t t = 0; t < trees; ++t) {
    const double r = between(2.5, 4.0);
    const Eigen::Vector4d f = place(2.0 * r, 2.0 * r, 1.0);
    const double x = 0.5 * (f[0] + f[2]), y = 0.5 * (f[1] + f[3]), g = ground.height(x, y);
    crowns.push_back({Vector3d(x, y, g + between(3.0, 6.0) + r), r, g - 0.5});
  }

  TerrainTile tile;
  const Vector3d offset(596000.0, 243000.0, 70.0);
  std::normal_distribution<double> noise(0.0, sigma);
  const double max_angle = 20.0 * std::numbers::pi / 180.0;
  while (tile.cloud.size() < n) {
    const double x = between(0.0, kTileSide), y = between(0.0, kTileSide), angle = between(-max_angle, max_angle);
    const bool through_crowns = u(rng) < 0.4;
    const double depth = u(rng), along = noise(rng);
    Ray ray;
    ray.direction = Vector3d(std::sin(angle), 0.0, -std::cos(angle));
    ray.origin = Vector3d(x, y, 0.0) - (kScannerHeight / std::cos(angle)) * ray.direction;
    Hit hit;
    for (const Box& box : boxes) hit_box(ray, box, hit);
    for (const Tree& tree : crowns) {
      if (!through_crowns) hit_crown(ray, tree, depth, hit);
      hit_trunk(ray, tree, hit);
    }
    hit_ground(ray, ground, hit);
    tile.cloud.positions.push_back(offset + ray.at(hit.t + along));
    tile.exact.push_back(hit.normal);
    tile.truth.push_back(hit.cls);
  }
  return tile;
}

double share_up(const TerrainTile& tile, const PointCloud& cloud, double cls, double min_exact_z) {
  std::size_t total = 0, up = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (tile.truth[i] != cls || tile.exact[i].z() < min_exact_z) continue;
    ++total;
    up += cloud.normals[i].z() > 0.0;
  }
  return total == 0 ? 1.0 : double(up) / double(total);
}

}  // namespace pointsurf::test
