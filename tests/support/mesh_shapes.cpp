// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/mesh_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <utility>

#include <Eigen/Geometry>

namespace pointsurf::test {
namespace {

// Flips every face of a convex, centred mesh to point away from `center`.
void orient_outward(TriangleMesh& mesh, const Vector3d& center) {
  for (Triangle& t : mesh.triangles) {
    const Vector3d &a = mesh.vertices.positions[std::size_t(t[0])], &b = mesh.vertices.positions[std::size_t(t[1])], &c = mesh.vertices.positions[std::size_t(t[2])];
    if ((b - a).cross(c - a).dot((a + b + c) / 3.0 - center) < 0.0) std::swap(t[1], t[2]);
  }
}

double segment_squared_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0.0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).squaredNorm();
}

}  // namespace

TriangleMesh cube_mesh(double half, const Vector3d& center) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.positions.push_back(center + half * Vector3d((i & 1) ? 1 : -1, (i & 2) ? 1 : -1, (i & 4) ? 1 : -1));
  // Each face as a quad of corner indices in cyclic order, split along one diagonal.
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.triangles.emplace_back(q[0], q[1], q[2]);
    m.triangles.emplace_back(q[0], q[2], q[3]);
  }
  orient_outward(m, center);
  return m;
}

TriangleMesh open_box_mesh(double half, const Vector3d& center) {
  TriangleMesh m = cube_mesh(half, center);
  std::vector<Triangle> kept;
  for (const Triangle& t : m.triangles) {
    bool top = true;
    for (int c = 0; c < 3; ++c) top = top && m.vertices.positions[std::size_t(t[c])].z() > center.z();
    if (!top) kept.push_back(t);
  }
  m.triangles = kept;
  return m;
}

TriangleMesh icosphere_mesh(int levels, double radius, const Vector3d& center) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                             {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vector3d& p : v) p.normalize();
  std::vector<Triangle> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                             {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
      return mid[key] = static_cast<int>(v.size() - 1);
    };
    std::vector<Triangle> next;
    for (const Triangle& t : f) {
      const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
      next.emplace_back(t[0], ab, ca);
      next.emplace_back(t[1], bc, ab);
      next.emplace_back(t[2], ca, bc);
      next.emplace_back(ab, bc, ca);
    }
    f = std::move(next);
  }
  TriangleMesh m;
  for (const Vector3d& p : v) m.vertices.positions.push_back(center + radius * p);
  m.triangles = f;
  orient_outward(m, center);
  return m;
}

TriangleMesh grid_mesh(int n, double half, const Vector3d& center) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      m.vertices.positions.push_back(center + Vector3d(-half + 2.0 * half * i / n, -half + 2.0 * half * j / n, 0.0));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
      m.triangles.emplace_back(a, b, c);
      m.triangles.emplace_back(a, c, d);
    }
  return m;
}

TriangleMesh random_soup(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0), small(-0.15, 0.15);
  TriangleMesh m;
  for (std::size_t t = 0; t < count; ++t) {
    const Vector3d c(u(rng), u(rng), u(rng));
    const int first = static_cast<int>(m.vertices.positions.size());
    for (int k = 0; k < 3; ++k) m.vertices.positions.push_back(c + Vector3d(small(rng), small(rng), small(rng)));
    m.triangles.emplace_back(first, first + 1, first + 2);
  }
  return m;
}

TriangleMesh join_meshes(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  const int shift = static_cast<int>(a.vertices.positions.size());
  m.vertices.positions.insert(m.vertices.positions.end(), b.vertices.positions.begin(), b.vertices.positions.end());
  for (const Triangle& t : b.triangles) m.triangles.emplace_back(t[0] + shift, t[1] + shift, t[2] + shift);
  return m;
}

double brute_force_squared_distance(const Vector3d& p, const TriangleMesh& mesh) {
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& t : mesh.triangles) {
    const Vector3d &a = mesh.vertices.positions[std::size_t(t[0])], &b = mesh.vertices.positions[std::size_t(t[1])], &c = mesh.vertices.positions[std::size_t(t[2])];
    const Vector3d n = (b - a).cross(c - a);
    if (n.squaredNorm() > 0.0) {
      const Vector3d unit = n.normalized();
      const Vector3d q = p - unit * unit.dot(p - a);
      // Inside when q lies on the inner side of all three edges.
      const bool inside = (b - a).cross(q - a).dot(n) >= 0.0 && (c - b).cross(q - b).dot(n) >= 0.0 && (a - c).cross(q - c).dot(n) >= 0.0;
      if (inside) best = std::min(best, (p - q).squaredNorm());
    }
    best = std::min({best, segment_squared_distance(p, a, b), segment_squared_distance(p, b, c), segment_squared_distance(p, c, a)});
  }
  return best;
}

double box_signed_distance(const Vector3d& p, double half, const Vector3d& center) {
  const Vector3d q = (p - center).cwiseAbs() - Vector3d::Constant(half);
  const double outside = q.cwiseMax(0.0).norm();
  const double inside = std::min(q.maxCoeff(), 0.0);
  return outside + inside;
}

TriangleMesh grid_cube(int n, double half) {
  TriangleMesh mesh;
  std::map<std::array<int, 3>, int> index;  // lattice point (0..n each) -> vertex
  auto vertex = [&](std::array<int, 3> q) {
    const auto it = index.find(q);
    if (it != index.end()) return it->second;
    mesh.vertices.positions.emplace_back(half * (2.0 * q[0] / n - 1.0), half * (2.0 * q[1] / n - 1.0), half * (2.0 * q[2] / n - 1.0));
    return index[q] = static_cast<int>(mesh.vertices.positions.size()) - 1;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;  // (u, w, axis) right-handed
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> q{};
            q[std::size_t(axis)] = side * n;
            q[std::size_t(u)] = i + di;
            q[std::size_t(w)] = j + dj;
            return vertex(q);
          };
          const int a = at(0, 0), b = at(1, 0), c = at(1, 1), d = at(0, 1);
          // u x w points along +axis: counter-clockwise from outside on the + side.
          if (side == 1) mesh.triangles.insert(mesh.triangles.end(), {Triangle(a, b, c), Triangle(a, c, d)});
          else mesh.triangles.insert(mesh.triangles.end(), {Triangle(a, c, b), Triangle(a, d, c)});
        }
    }
  return mesh;
}

}  // namespace pointsurf::test
