// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/flat_regions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "reconstruct/detail/face_edges.h"

namespace pointsurf {

const FieldTable<FlatRegionParams>& FlatRegionParams::fields() {
  static const FieldTable<FlatRegionParams> table = [] {
    using P = FlatRegionParams;
    FieldTable<P> t;
    t.number("region_normal_angle_deg", &P::max_normal_angle_deg, "Flat regions: largest normal angle across an edge")
        .unit("degrees")
        .range(0, 180, true, false);
    t.number("region_seed_angle_deg", &P::max_seed_angle_deg, "Flat regions: largest normal angle to the region's seed face; 180: off")
        .unit("degrees")
        .range(0, 180, true, false);
    return t;
  }();
  return table;
}

void FlatRegionParams::validate() const {
  const auto check = [](const char* name, double value) {
    if (!(value > 0.0 && value <= 180.0))
      throw UsageError(fmt::format("label_flat_regions: {} must be in (0, 180], got {}", name, value));
  };
  check("max_normal_angle_deg", max_normal_angle_deg);
  check("max_seed_angle_deg", max_seed_angle_deg);
  fields().validate(*this, "label_flat_regions");
}

namespace {

struct FaceGeometry {
  Vector3d normal = Vector3d::Zero();  // unit, zero for a face without area
  double area = 0.0;
  Vector3d centroid = Vector3d::Zero();
  double flatness = -2.0;  // smallest cosine to an edge neighbour (1 without neighbours); -2 no normal
};

}  // namespace

FlatRegionResult label_flat_regions(const TriangleMesh& mesh, const FlatRegionParams& params, const ProgressCallback& progress) {
  const auto report = [&](double fraction) {
    if (progress && !progress(fraction)) throw CancelledError("label_flat_regions: cancelled");
  };
  params.validate();
  mesh.validate();
  FlatRegionResult result;
  const std::size_t f = mesh.triangles.size();
  if (f == 0) return result;
  const auto cosine = [](double deg) { return std::cos(deg * std::numbers::pi / 180.0); };
  const double min_cos = cosine(params.max_normal_angle_deg);
  const double min_seed_cos = cosine(params.max_seed_angle_deg);

  std::vector<FaceGeometry> geo(f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      const Triangle& tri = mesh.triangles[t];
      const Vector3d& a = mesh.vertices.positions[std::size_t(tri[0])];
      // Edge vectors, not positions: a mesh 1e6 m from the origin gets the same normals.
      const Vector3d cross = (mesh.vertices.positions[std::size_t(tri[1])] - a).cross(mesh.vertices.positions[std::size_t(tri[2])] - a);
      const double norm = cross.norm();
      FaceGeometry& g = geo[t];
      g.centroid = (a + mesh.vertices.positions[std::size_t(tri[1])] + mesh.vertices.positions[std::size_t(tri[2])]) / 3.0;
      if (norm > 0.0 && std::isfinite(norm)) {
        g.normal = cross / norm;
        g.area = 0.5 * norm;
      }
    }
  });

  report(0.1);
  // Neighbours across manifold edges only: a boundary edge has none, and on a non-manifold
  // edge no pair of its faces is the surface's continuation more than another.
  std::vector<std::array<int, 3>> neighbours(f, std::array<int, 3>{-1, -1, -1});
  {
    const std::vector<detail::FaceEdge> edges = detail::sorted_face_edges(mesh);
    const auto add_neighbour = [&](int face, int other) {
      for (int& slot : neighbours[std::size_t(face)])
        if (slot < 0) { slot = other; return; }
    };
    detail::for_each_edge(edges, [&](std::size_t begin, std::size_t end) {
      if (end - begin != 2 || edges[begin].face == edges[begin + 1].face) return;
      add_neighbour(edges[begin].face, edges[begin + 1].face);
      add_neighbour(edges[begin + 1].face, edges[begin].face);
    });
  }
  const auto has_normal = [&](std::size_t t) { return geo[t].area > 0.0; };
  report(0.35);

  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t < r.end(); ++t) {
      if (!has_normal(t)) continue;
      double flatness = 1.0;
      for (const int n : neighbours[t])
        if (n >= 0 && has_normal(std::size_t(n))) flatness = std::min(flatness, geo[t].normal.dot(geo[std::size_t(n)].normal));
      geo[t].flatness = flatness;
    }
  });

  report(0.4);
  // Seeds flattest first, then largest, then by centroid: an order of the geometry, not of the
  // face indices, so that a permutation of the faces gives the same regions.
  std::vector<int> order(f);
  std::iota(order.begin(), order.end(), 0);
  tbb::parallel_sort(order.begin(), order.end(), [&](int x, int y) {
    const FaceGeometry& a = geo[std::size_t(x)];
    const FaceGeometry& b = geo[std::size_t(y)];
    if (a.flatness != b.flatness) return a.flatness > b.flatness;
    if (a.area != b.area) return a.area > b.area;
    for (int c = 0; c < 3; ++c)
      if (a.centroid[c] != b.centroid[c]) return a.centroid[c] < b.centroid[c];
    return x < y;
  });

  // A region is the set of unlabelled faces in the seed's cone that the seed reaches across
  // joinable edges: a fixed set, whatever order the stack visits it in.
  report(0.7);
  std::vector<int> label(f, -1);
  std::vector<int> stack;
  int regions = 0;
  std::size_t seeds_seen = 0;
  for (const int seed : order) {
    if ((++seeds_seen & 0x3ffffu) == 0) report(0.7 + 0.25 * double(seeds_seen) / double(f));
    if (label[std::size_t(seed)] >= 0) continue;
    const int r = regions++;
    label[std::size_t(seed)] = r;
    if (!has_normal(std::size_t(seed))) continue;
    const Vector3d& seed_normal = geo[std::size_t(seed)].normal;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      for (const int n : neighbours[std::size_t(t)]) {
        if (n < 0 || label[std::size_t(n)] >= 0 || !has_normal(std::size_t(n))) continue;
        const Vector3d& normal = geo[std::size_t(n)].normal;
        if (normal.dot(geo[std::size_t(t)].normal) < min_cos || normal.dot(seed_normal) < min_seed_cos) continue;
        label[std::size_t(n)] = r;
        stack.push_back(n);
      }
    }
  }

  report(0.95);
  // Numbered by each region's smallest face index.
  std::vector<int> renumber(std::size_t(regions), -1);
  std::vector<std::size_t> sizes(std::size_t(regions), 0);
  result.region.resize(f);
  int next = 0;
  for (std::size_t t = 0; t < f; ++t) {
    int& id = renumber[std::size_t(label[t])];
    if (id < 0) id = next++;
    result.region[t] = id;
    ++sizes[std::size_t(id)];
  }
  result.regions = std::size_t(regions);
  result.largest_region = *std::max_element(sizes.begin(), sizes.end());
  return result;
}

const ResultTable<FlatRegionResult>& FlatRegionResult::results() {
  static const ResultTable<FlatRegionResult> table = [] {
    ResultTable<FlatRegionResult> t;
    t.count("regions", &FlatRegionResult::regions, "Flat regions labelled (face field region)").as_count();
    t.count("largest_region_faces", &FlatRegionResult::largest_region, "Faces of the largest region").as_count();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
