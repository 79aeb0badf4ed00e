// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/reconstruct/run_triangulate_bench.sh.
//   triangulate_runner run CLOUD.ply OUT.ply [KEY=VALUE...]        the cloud's own oriented normals
//   triangulate_runner shape NAME N OUT.ply SEED [KEY=VALUE...]    sphere, torus, cube, plane; exact normals
//                                                                  (NAME_estimated: PCA normals, k = 15, oriented;
//                                                                  a first KEY noise=S: Gaussian noise of S mean spacings)
// Runs reconstruct_region_growing (default parameters unless a TriangulateParams field is set as
// KEY=VALUE) and writes the mesh ("-": not written). Prints one JSON
// line: seconds (whole reconstruction, file reading excluded), peak_rss_mb (whole process), the
// stage counts, the mesh topology and the boundary loops (corner count, perimeter in mean
// spacings, centroid), longest first, at most 20.
#include <sys/resource.h>

#include <array>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/reconstruct/triangulate.h"
#include "../bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;

using namespace pointsurf;

// The same samplers (and RNG draw order) as tests/support/shapes.cpp, so that a shape here is
// the cloud of the test of the same size and seed.
PointCloud sample(const std::string& name, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  PointCloud cloud;
  if (name == "sphere") {
    std::normal_distribution<double> g(0.0, 1.0);
    while (cloud.positions.size() < n) {
      Vector3d v(g(rng), g(rng), g(rng));
      const double len = v.norm();
      if (len < 1e-12) continue;
      v /= len;
      cloud.positions.push_back(v);
      cloud.normals.push_back(v);
    }
  } else if (name == "plane") {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
      const double x = u(rng);
      const double y = u(rng);
      cloud.positions.emplace_back(x, y, 0.0);
      cloud.normals.emplace_back(0.0, 0.0, 1.0);
    }
  } else if (name == "cube") {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::uniform_int_distribution<int> face(0, 5);
    for (std::size_t i = 0; i < n; ++i) {
      const int f = face(rng);
      const int axis = f / 2;
      const double sign = (f % 2 == 0) ? 1.0 : -1.0;
      const double a = u(rng);
      const double b = u(rng);
      Vector3d p, nrm = Vector3d::Zero();
      p[axis] = sign;
      p[(axis + 1) % 3] = a;
      p[(axis + 2) % 3] = b;
      nrm[axis] = sign;
      cloud.positions.push_back(p);
      cloud.normals.push_back(nrm);
    }
  } else if (name == "torus") {
    const double major = 1.0, minor = 0.35;
    std::uniform_real_distribution<double> u01(0.0, 1.0);
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
  } else {
    throw UsageError(fmt::format("triangulate_runner: unknown shape '{}' (sphere, torus, cube, plane)", name));
  }
  return cloud;
}

// KEY=VALUE overrides of the defaults, for experiments.
TriangulateParams parse_params(int argc, char** argv, int first) {
  TriangulateParams p;
  for (int i = first; i < argc; ++i) {
    const std::string arg = argv[i];
    const std::size_t eq = arg.find('=');
    if (eq == std::string::npos) throw UsageError(fmt::format("triangulate_runner: expected KEY=VALUE, got '{}'", arg));
    const std::string key = arg.substr(0, eq);
    const double value = std::stod(arg.substr(eq + 1));
    if (key == "k") p.k = int(value);
    else if (key == "radius") p.radius = Length::cloud(value);
    else if (key == "radius_in_spacings") p.radius = Length::spacings(value);
    else if (key == "max_offset_in_spacings") p.max_offset_in_spacings = value;
    else if (key == "max_normal_angle_deg") p.max_normal_angle_deg = value;
    else if (key == "min_angle_deg") p.min_angle_deg = value;
    else if (key == "max_angle_deg") p.max_angle_deg = value;
    else if (key == "max_dihedral_deg") p.max_dihedral_deg = value;
    else if (key == "max_front_angle_deg") p.max_front_angle_deg = value;
    else if (key == "max_hole_perimeter_in_spacings") p.max_hole_perimeter_in_spacings = value;
    else throw UsageError(fmt::format("triangulate_runner: unknown parameter '{}'", key));
  }
  return p;
}

int run(const PointCloud& cloud, const std::string& out_path, const TriangulateParams& params) {
  // Stage ends from the progress fractions: 0.1 spacing, 0.7 umbrellas, 0.8 merging the
  // candidates, 0.9 growing, 1.0 closing holes and topology.
  const std::array<double, 5> marks{0.1, 0.7, 0.8, 0.9, 1.0};
  std::array<double, 5> stage_end{};
  std::size_t next_mark = 0;
  const Clock::time_point start = Clock::now();
  const auto progress = [&](double fraction) {
    while (next_mark < marks.size() && fraction >= marks[next_mark] - 1e-12)
      stage_end[next_mark++] = std::chrono::duration<double>(Clock::now() - start).count();
    return true;
  };
  const TriangulateResult result = reconstruct_region_growing(cloud, params, nullptr, progress);
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const double rss = peak_rss_mb();
  if (!out_path.empty() && out_path != "-") write_mesh(out_path, result.mesh);
  const MeshTopology& t = result.topology;
  nlohmann::json out;
  out["tool"] = "pointsurf";
  out["points"] = cloud.size();
  out["seconds"] = seconds;
  out["peak_rss_mb"] = rss;
  out["stage_seconds"] = {{"tree_and_spacing", stage_end[0]},
                          {"umbrellas", stage_end[1] - stage_end[0]},
                          {"merge_candidates", stage_end[2] - stage_end[1]},
                          {"grow", stage_end[3] - stage_end[2]},
                          {"close_holes", stage_end[4] - stage_end[3]}};
  out["mean_spacing"] = result.mean_spacing;
  out["candidate_triangles"] = result.candidate_triangles;
  out["selected_triangles"] = result.selected_triangles;
  out["front_triangles"] = result.front_triangles;
  out["holes_filled"] = result.holes_filled;
  out["fill_triangles"] = result.fill_triangles;
  out["pinch_triangles_removed"] = result.pinch_triangles_removed;
  out["inserted_points"] = result.inserted_points;
  out["triangles"] = t.triangles;
  out["unused_points"] = result.unused_points;
  out["boundary_edges"] = t.boundary_edges;
  out["boundary_loops"] = t.boundary_loops.size();
  out["non_manifold_edges"] = t.non_manifold_edges;
  out["non_manifold_vertices"] = t.non_manifold_vertices;
  out["inconsistent_edges"] = t.inconsistent_edges;
  out["components"] = t.components;
  out["euler_characteristic"] = t.euler_characteristic;
  nlohmann::json loops = nlohmann::json::array();
  for (std::size_t i = 0; i < t.boundary_loops.size() && i < 20; ++i) {
    const BoundaryLoop& loop = t.boundary_loops[i];
    Vector3d centroid = Vector3d::Zero();
    for (int v : loop.vertices) centroid += result.mesh.vertices.positions[std::size_t(v)];
    centroid /= double(loop.vertices.size());
    loops.push_back({{"corners", loop.vertices.size()},
                     {"perimeter_in_spacings", loop.length / result.mean_spacing},
                     {"centroid", {centroid.x(), centroid.y(), centroid.z()}}});
  }
  out["loops"] = loops;
  fmt::print("{}\n", out.dump());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "run" && argc >= 4) return run(read_point_cloud(argv[2]).cloud, argv[3], parse_params(argc, argv, 4));
    if (mode == "shape" && argc >= 6) {
      // A NAME ending in "_estimated" replaces the exact normals by PCA normals (k = 15), oriented.
      std::string name = argv[2];
      const std::string suffix = "_estimated";
      const bool estimated = name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
      if (estimated) name.resize(name.size() - suffix.size());
      PointCloud cloud = sample(name, std::stoul(argv[3]), std::stoull(argv[5]));
      // A first extra argument noise=S adds Gaussian noise of S mean spacings (seeded) to the
      // positions, normals kept.
      int first_param = 6;
      if (argc > 6 && std::string(argv[6]).rfind("noise=", 0) == 0) {
        const double sigma = std::stod(std::string(argv[6]).substr(6)) * mean_spacing(cloud.positions);
        std::mt19937_64 rng(std::stoull(argv[5]) + 1000);
        std::normal_distribution<double> gauss(0.0, sigma);
        for (Vector3d& p : cloud.positions) {
          const double x = gauss(rng), y = gauss(rng), z = gauss(rng);
          p += Vector3d(x, y, z);
        }
        first_param = 7;
      }
      if (estimated) {
        cloud.normals.clear();
        NormalParams normal_params;
        normal_params.k = 15;
        estimate_normals(cloud, normal_params);
        orient_normals(cloud);
      }
      return run(cloud, argv[4], parse_params(argc, argv, first_param));
    }
    fmt::print(stderr, "usage: triangulate_runner run CLOUD.ply OUT.ply [KEY=VALUE...] | "
                       "shape sphere|torus|cube|plane N OUT.ply SEED [KEY=VALUE...]\n");
    return 1;
  } catch (const Error& e) {
    fmt::print(stderr, "triangulate_runner: {}\n", e.what());
    return e.exit_code();
  }
}
