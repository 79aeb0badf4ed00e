// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/mesh_shapes.h"

#include <array>
#include <cmath>
#include <map>
#include <utility>

namespace pointsurf::test {

TriangleMesh icosphere(int levels, double radius, const Vector3d& center) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vector3d> v = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                             {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
  for (Vector3d& p : v) p.normalize();
  std::vector<Triangle> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                             {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                             {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<int, int>, int> middle;
    auto mid = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = middle.find(key);
      if (it != middle.end()) return it->second;
      v.push_back((v[std::size_t(a)] + v[std::size_t(b)]).normalized());
      return middle[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Triangle> next;
    for (const Triangle& t : f) {
      const int ab = mid(t[0], t[1]), bc = mid(t[1], t[2]), ca = mid(t[2], t[0]);
      next.insert(next.end(), {Triangle(t[0], ab, ca), Triangle(t[1], bc, ab), Triangle(t[2], ca, bc), Triangle(ab, bc, ca)});
    }
    f = std::move(next);
  }
  TriangleMesh mesh;
  for (const Vector3d& p : v) mesh.vertices.push_back(center + radius * p);
  mesh.triangles = std::move(f);
  return mesh;
}

TriangleMesh grid_cube(int n, double half) {
  TriangleMesh mesh;
  std::map<std::array<int, 3>, int> index;  // lattice point (0..n each) -> vertex
  auto vertex = [&](std::array<int, 3> q) {
    const auto it = index.find(q);
    if (it != index.end()) return it->second;
    mesh.vertices.emplace_back(half * (2.0 * q[0] / n - 1.0), half * (2.0 * q[1] / n - 1.0), half * (2.0 * q[2] / n - 1.0));
    return index[q] = static_cast<int>(mesh.vertices.size()) - 1;
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
