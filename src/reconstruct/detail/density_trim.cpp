// SPDX-License-Identifier: GPL-3.0-or-later
// Trimming by a vertex field, PoissonRecon's SurfaceTrimmer semantics (reconstruct/detail/density_trim.h).
#include "reconstruct/detail/density_trim.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "pointsurf/core/error.h"

namespace pointsurf::detail {
namespace {

struct Piece {
  std::array<int, 3> v;  // indices into the original vertices, then the cut vertices
  int parent;            // input triangle
  bool above;            // on the kept side of the level line
};

struct Cut {
  int a, b;   // original vertices, a < b
  double t;   // position a + t (b - a)
};

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

int find(std::vector<int>& parent, int x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

}  // namespace

TrimResult trim_by_vertex_field(TriangleMesh& mesh, std::string_view field, double level, double island_area_ratio,
                                int smooth_iterations) {
  const ScalarField* source = mesh.vertices.fields.find(field);
  if (!source) throw InputError("trim_by_vertex_field: the mesh has no vertex field '" + std::string(field) + "'");
  if (!(island_area_ratio >= 0.0)) throw UsageError("trim_by_vertex_field: island_area_ratio must be >= 0");
  if (smooth_iterations < 0) throw UsageError("trim_by_vertex_field: smooth_iterations must be >= 0");
  mesh.validate();
  const int vertex_count = static_cast<int>(mesh.vertices.positions.size());

  // 1. The field, smoothed as SurfaceTrimmer does: the mean of the edge neighbours' values.
  std::vector<double> value = source->values;
  for (int it = 0; it < smooth_iterations; ++it) {
    std::vector<double> sum(value.size(), 0.0);
    std::vector<int> count(value.size(), 0);
    for (const Triangle& t : mesh.triangles)
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        sum[a] += value[b], sum[b] += value[a];
        ++count[a], ++count[b];
      }
    for (std::size_t v = 0; v < value.size(); ++v)
      if (count[v] > 0) value[v] = sum[v] / count[v];
  }
  auto above = [&](int v) { return value[v] >= level; };

  // 2. Cut every triangle along the level line into a part above and a part below.
  TrimResult result;
  std::vector<Piece> pieces;
  pieces.reserve(mesh.triangles.size() + mesh.triangles.size() / 4);
  std::vector<Cut> cuts;
  std::unordered_map<std::uint64_t, int> cut_of;
  auto cut_vertex = [&](int a, int b) {
    const auto [it, inserted] = cut_of.emplace(edge_key(a, b), vertex_count + static_cast<int>(cuts.size()));
    if (inserted) {
      const int lo = std::min(a, b), hi = std::max(a, b);
      const double t = (level - value[lo]) / (value[hi] - value[lo]);
      cuts.push_back({lo, hi, std::clamp(t, 0.0, 1.0)});
    }
    return it->second;
  };
  for (int f = 0; f < static_cast<int>(mesh.triangles.size()); ++f) {
    const Triangle& t = mesh.triangles[f];
    const int up = int(above(t[0])) + int(above(t[1])) + int(above(t[2]));
    if (up == 0 || up == 3) {
      pieces.push_back({{t[0], t[1], t[2]}, f, up == 3});
      continue;
    }
    ++result.cut_triangles;
    // Rotate so that t[k] is the vertex alone on its side, then cut its two edges.
    int k = 0;
    while (above(t[k]) == (up == 2)) ++k;
    const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
    const int p = cut_vertex(a, b), q = cut_vertex(c, a);
    const bool lone_above = up == 1;
    pieces.push_back({{a, p, q}, f, lone_above});
    pieces.push_back({{p, b, c}, f, !lone_above});
    pieces.push_back({{p, c, q}, f, !lone_above});
  }

  std::vector<Eigen::Vector3d> position(mesh.vertices.positions.begin(), mesh.vertices.positions.end());
  for (const Cut& c : cuts) position.push_back(mesh.vertices.positions[c.a] + c.t * (mesh.vertices.positions[c.b] - mesh.vertices.positions[c.a]));

  // 3. Islands: components of each side (pieces sharing an edge), measured against the total area.
  std::vector<char> keep(pieces.size());
  for (std::size_t i = 0; i < pieces.size(); ++i) keep[i] = pieces[i].above;
  if (island_area_ratio > 0.0) {
    std::vector<std::pair<std::uint64_t, int>> edges;
    edges.reserve(3 * pieces.size());
    for (int i = 0; i < static_cast<int>(pieces.size()); ++i)
      for (int k = 0; k < 3; ++k) edges.emplace_back(edge_key(pieces[i].v[k], pieces[i].v[(k + 1) % 3]), i);
    std::sort(edges.begin(), edges.end());
    std::vector<int> parent(pieces.size());
    std::iota(parent.begin(), parent.end(), 0);
    for (std::size_t i = 0; i < edges.size();) {
      std::size_t j = i;
      while (j < edges.size() && edges[j].first == edges[i].first) ++j;
      for (std::size_t k = i + 1; k < j; ++k) {
        const int x = edges[i].second, y = edges[k].second;
        if (pieces[x].above == pieces[y].above) parent[find(parent, x)] = find(parent, y);
      }
      i = j;
    }
    std::vector<double> area(pieces.size(), 0.0);
    double total = 0.0;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const auto& v = pieces[i].v;
      const double a = 0.5 * (position[v[1]] - position[v[0]]).cross(position[v[2]] - position[v[0]]).norm();
      area[find(parent, static_cast<int>(i))] += a;
      total += a;
    }
    std::vector<char> counted(pieces.size(), 0);
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      const int root = find(parent, static_cast<int>(i));
      const bool small = area[root] < island_area_ratio * total;
      if (small) keep[i] = !pieces[i].above;
      if (small && !counted[root]) {
        counted[root] = 1;
        ++(pieces[i].above ? result.removed_islands : result.filled_holes);
      }
    }
  }

  // 4. The kept pieces, with the vertices they use (originals first, then cut vertices).
  std::vector<char> parent_kept(mesh.triangles.size(), 0);
  std::vector<int> new_index(position.size(), -1);
  for (std::size_t i = 0; i < pieces.size(); ++i)
    if (keep[i]) {
      parent_kept[pieces[i].parent] = 1;
      for (int v : pieces[i].v) new_index[v] = 0;
    }
  result.removed_triangles = static_cast<std::size_t>(std::count(parent_kept.begin(), parent_kept.end(), 0));
  std::vector<int> old_of;
  for (int v = 0; v < static_cast<int>(position.size()); ++v)
    if (new_index[v] == 0) new_index[v] = static_cast<int>(old_of.size()), old_of.push_back(v);

  auto lerp_or_copy = [&](auto& values, auto&& lerp) {
    using Vec = std::decay_t<decltype(values)>;
    if (values.empty()) return;
    Vec out;
    out.reserve(old_of.size());
    for (int v : old_of) {
      if (v < vertex_count) {
        out.push_back(values[v]);
      } else {
        const Cut& c = cuts[v - vertex_count];
        out.push_back(lerp(values[c.a], values[c.b], c.t));
      }
    }
    values = std::move(out);
  };
  std::vector<Eigen::Vector3d> vertices;
  vertices.reserve(old_of.size());
  for (int v : old_of) vertices.push_back(position[v]);
  mesh.vertices.positions = std::move(vertices);
  lerp_or_copy(mesh.vertices.normals, [](const Vector3d& a, const Vector3d& b, double t) {
    const Vector3d n = (1 - t) * a + t * b;
    return Vector3d(n.norm() > 0.0 ? Vector3d(n.normalized()) : a);
  });
  lerp_or_copy(mesh.vertices.colors,
               [](const Vector3f& a, const Vector3f& b, double t) { return Vector3f((1 - float(t)) * a + float(t) * b); });
  for (ScalarField& f : mesh.vertices.fields) {
    const bool real = scalar_type_is_float(f.type);
    lerp_or_copy(f.values, [real](double a, double b, double t) { return real ? (1 - t) * a + t * b : (t < 0.5 ? a : b); });
  }
  std::vector<Triangle> triangles;
  std::vector<int> parents;
  for (std::size_t i = 0; i < pieces.size(); ++i)
    if (keep[i]) {
      const auto& v = pieces[i].v;
      triangles.emplace_back(new_index[v[0]], new_index[v[1]], new_index[v[2]]);
      parents.push_back(pieces[i].parent);
    }
  for (ScalarField& f : mesh.face_fields) {
    std::vector<double> values;
    values.reserve(parents.size());
    for (int p : parents) values.push_back(f.values[p]);
    f.values = std::move(values);
  }
  mesh.triangles = std::move(triangles);
  return result;
}

}  // namespace pointsurf::detail
