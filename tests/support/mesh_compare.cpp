// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/mesh_compare.h"

#include <algorithm>
#include <limits>

#include <Eigen/Geometry>

#include "support/distances.h"

namespace pointsurf::test {

std::set<std::array<int, 3>> oriented_triangle_set(const TriangleMesh& mesh, const std::vector<int>& to_original) {
  std::set<std::array<int, 3>> s;
  for (const Triangle& t : mesh.triangles) {
    std::array<int, 3> a{t[0], t[1], t[2]};
    if (!to_original.empty())
      for (int& v : a) v = to_original[std::size_t(v)];
    std::rotate(a.begin(), std::min_element(a.begin(), a.end()), a.end());
    s.insert(a);
  }
  return s;
}

std::pair<double, double> hausdorff_to_surface(const TriangleMesh& mesh, const std::vector<Vector3d>& truth,
                                               const std::function<double(const Vector3d&)>& distance) {
  const auto on_mesh = sample_mesh_surface(mesh.vertices.positions, mesh.triangles, 100000);
  double to_truth = 0.0;
  for (const auto& x : on_mesh) to_truth = std::max(to_truth, distance(x));
  const auto back = nearest_distances(truth, on_mesh);
  const double from_truth = back.empty() ? std::numeric_limits<double>::infinity() : *std::max_element(back.begin(), back.end());
  return {to_truth, from_truth};
}

std::size_t inward_faces(const TriangleMesh& mesh, const Vector3d& centre) {
  std::size_t count = 0;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d& a = mesh.vertices.positions[std::size_t(t[0])];
    const Vector3d n = (mesh.vertices.positions[std::size_t(t[1])] - a).cross(mesh.vertices.positions[std::size_t(t[2])] - a);
    if (n.dot((a + mesh.vertices.positions[std::size_t(t[1])] + mesh.vertices.positions[std::size_t(t[2])]) / 3.0 - centre) < 0) ++count;
  }
  return count;
}

}  // namespace pointsurf::test
