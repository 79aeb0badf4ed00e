// SPDX-License-Identifier: GPL-3.0-or-later
// mesh_metrics_runner RESULT_MESH REFERENCE_MESH [samples]
//
// Quality of a reconstructed mesh against the true (reference) mesh, as one JSON object on
// stdout: the result's topology (analyze_topology: boundary edges, holes, non-manifold edges
// and vertices, orientation, components, Euler characteristic), its triangle-angle figures, and
// Chamfer / Hausdorff distances between the two surfaces. Both meshes are sampled area-uniformly
// (`samples` points each, default 200000, seeded: evaluate's sample_mesh_surface), and each
// sample's distance is the exact point-to-triangle distance to the other mesh (evaluate's
// TriangleBvh, through nearest_surface_distances).
// Used by every reconstruction benchmark in bench/reconstruct/; the interface stays stable.
// Exit codes: 0 ok, 1 usage, 2 unreadable input.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/io/io.h"

namespace {

using pointsurf::Vector3d;

struct Mesh {
  std::vector<Vector3d> vertices;  // shifted by the common origin
  std::vector<Eigen::Vector3i> triangles;
};

double surface_area(const Mesh& m) {
  double total = 0.0;
  for (const Eigen::Vector3i& f : m.triangles)
    total += 0.5 * (m.vertices[f[1]] - m.vertices[f[0]]).cross(m.vertices[f[2]] - m.vertices[f[0]]).norm();
  return total;
}

struct OneSided {
  double mean = 0.0, rms = 0.0, max = 0.0, p95 = 0.0;
};

// Exact distances from `samples` to the surface of `target`.
OneSided distances_to(const std::vector<Vector3d>& samples, const Mesh& target) {
  OneSided out;
  if (samples.empty()) return out;
  if (target.triangles.empty()) {
    out.mean = out.rms = out.max = out.p95 = INFINITY;
    return out;
  }
  std::vector<double> d = pointsurf::nearest_surface_distances(samples, pointsurf::SurfaceView{target.vertices, target.triangles});
  double sum = 0.0, sq = 0.0;
  for (double v : d) { sum += v; sq += v * v; out.max = std::max(out.max, v); }
  out.mean = sum / double(d.size());
  out.rms = std::sqrt(sq / double(d.size()));
  std::sort(d.begin(), d.end());
  out.p95 = pointsurf::percentile_of_sorted(d, 95);
  return out;
}

nlohmann::json one_sided_json(const OneSided& s) { return {{"mean", s.mean}, {"rms", s.rms}, {"p95", s.p95}, {"max", s.max}}; }

// Inner-angle figures of the result's triangles: the smallest angle of each triangle.
nlohmann::json angle_figures(const Mesh& m) {
  if (m.triangles.empty()) return nlohmann::json::object();
  std::size_t below_10 = 0, below_20 = 0;
  double sum_min = 0.0, worst = 180.0;
  for (const Eigen::Vector3i& f : m.triangles) {
    double smallest = 180.0;
    for (int c = 0; c < 3; ++c) {
      const Vector3d u = m.vertices[f[(c + 1) % 3]] - m.vertices[f[c]], v = m.vertices[f[(c + 2) % 3]] - m.vertices[f[c]];
      const double nu = u.norm(), nv = v.norm();
      if (nu == 0.0 || nv == 0.0) { smallest = 0.0; continue; }
      smallest = std::min(smallest, std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * 180.0 / std::numbers::pi);
    }
    sum_min += smallest;
    worst = std::min(worst, smallest);
    below_10 += smallest < 10.0;
    below_20 += smallest < 20.0;
  }
  const double n = double(m.triangles.size());
  return {{"mean_min_angle_deg", sum_min / n}, {"worst_min_angle_deg", worst}, {"share_min_angle_below_10_deg", double(below_10) / n},
          {"share_min_angle_below_20_deg", double(below_20) / n}};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3 || argc > 4) {
    std::fprintf(stderr, "usage: mesh_metrics_runner RESULT_MESH REFERENCE_MESH [samples]\n");
    return 1;
  }
  std::size_t samples = 200000;
  if (argc == 4) {
    try {
      const long long v = std::stoll(argv[3]);
      if (v < 1) throw std::invalid_argument("");
      samples = std::size_t(v);
    } catch (const std::exception&) {
      std::fprintf(stderr, "mesh_metrics_runner: samples: '%s' must be a positive integer\n", argv[3]);
      return 1;
    }
  }
  try {
    pointsurf::MeshReadResult result = pointsurf::read_mesh(argv[1]);
    pointsurf::MeshReadResult reference = pointsurf::read_mesh(argv[2]);
    const pointsurf::MeshTopology topo = pointsurf::analyze_topology(result.mesh);

    // A common local origin keeps georeferenced meshes precise in the distance computations.
    const pointsurf::BoundingBox box = pointsurf::bounding_box(reference.mesh.vertices.positions);
    const Vector3d origin = box.center();
    Mesh a{result.mesh.vertices.positions, result.mesh.triangles}, b{reference.mesh.vertices.positions, reference.mesh.triangles};
    for (Vector3d& v : a.vertices) v -= origin;
    for (Vector3d& v : b.vertices) v -= origin;
    const double area_a = surface_area(a), area_b = surface_area(b);
    const std::vector<Vector3d> sa = pointsurf::sample_mesh_surface(a.vertices, a.triangles, samples, 11),
                                sb = pointsurf::sample_mesh_surface(b.vertices, b.triangles, samples, 12);
    const OneSided ab = distances_to(sa, b), ba = distances_to(sb, a);
    const double diagonal = box.diagonal();

    nlohmann::json holes = nlohmann::json::array();
    double hole_perimeter = 0.0;
    for (const pointsurf::BoundaryLoop& loop : topo.boundary_loops) hole_perimeter += loop.length;
    nlohmann::json out = {
        {"result", argv[1]},
        {"reference", argv[2]},
        {"samples", samples},
        {"vertices", result.mesh.vertices.positions.size()},
        {"triangles", topo.triangles},
        {"degenerate_triangles", topo.degenerate_triangles},
        {"used_vertices", topo.vertices},
        {"isolated_vertices", topo.isolated_vertices},
        {"edges", topo.edges},
        {"boundary_edges", topo.boundary_edges},
        {"boundary_loops", topo.boundary_loops.size()},
        {"boundary_total_length", hole_perimeter},
        {"largest_boundary_length", topo.boundary_loops.empty() ? 0.0 : topo.boundary_loops.front().length},
        {"non_manifold_edges", topo.non_manifold_edges},
        {"non_manifold_vertices", topo.non_manifold_vertices},
        {"inconsistent_edges", topo.inconsistent_edges},
        {"components", topo.components},
        {"euler_characteristic", topo.euler_characteristic},
        {"genus", topo.genus()},
        {"watertight", topo.watertight()},
        {"area", area_a},
        {"reference_area", area_b},
        {"reference_diagonal", diagonal},
        {"result_to_reference", one_sided_json(ab)},
        {"reference_to_result", one_sided_json(ba)},
        {"chamfer", 0.5 * (ab.mean + ba.mean)},
        {"hausdorff", std::max(ab.max, ba.max)},
        {"chamfer_rel_diagonal", diagonal > 0.0 ? 0.5 * (ab.mean + ba.mean) / diagonal : 0.0},
        {"hausdorff_rel_diagonal", diagonal > 0.0 ? std::max(ab.max, ba.max) / diagonal : 0.0},
        {"angles", angle_figures(a)},
    };
    std::printf("%s\n", out.dump(2).c_str());
  } catch (const pointsurf::Error& e) {
    std::fprintf(stderr, "mesh_metrics_runner: %s\n", e.what());
    return e.exit_code();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_metrics_runner: %s\n", e.what());
    return 3;
  }
  return 0;
}
