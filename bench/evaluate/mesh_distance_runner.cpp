// SPDX-License-Identifier: GPL-3.0-or-later
// mesh_distance_runner prepare MESH.off LEVELS OUT_MESH.ply N OUT_POINTS.ply SEED
//   Splits every triangle of MESH into 4, LEVELS times (the surface is unchanged), writes it, and
//   N query points: area-uniform samples (seeded) moved along their face normal by a uniform
//   offset in [-2%, 2%] of the bounding-box diagonal.
// mesh_distance_runner time MESH.ply POINTS.ply MODE OUT.bin
//   MODE unsigned | signed | winding. Times the hierarchy build plus the distances (file
//   reading excluded), writes the N distances as float64 to OUT.bin and prints one JSON object.
// Exit codes: 0 ok, 1 usage, 2 unreadable input.
#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "../bench_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/io/io.h"

namespace {

using namespace pointsurf;

TriangleMesh split_in_four(const TriangleMesh& m) {
  TriangleMesh out;
  out.vertices.positions = m.vertices.positions;
  std::map<std::pair<int, int>, int> mid;
  auto midpoint = [&](int a, int b) {
    const auto key = std::make_pair(std::min(a, b), std::max(a, b));
    const auto it = mid.find(key);
    if (it != mid.end()) return it->second;
    out.vertices.positions.push_back(0.5 * (m.vertices.positions[std::size_t(a)] + m.vertices.positions[std::size_t(b)]));
    return mid[key] = static_cast<int>(out.vertices.positions.size() - 1);
  };
  for (const Triangle& t : m.triangles) {
    const int ab = midpoint(t[0], t[1]), bc = midpoint(t[1], t[2]), ca = midpoint(t[2], t[0]);
    out.triangles.emplace_back(t[0], ab, ca);
    out.triangles.emplace_back(t[1], bc, ab);
    out.triangles.emplace_back(t[2], ca, bc);
    out.triangles.emplace_back(ab, bc, ca);
  }
  return out;
}

int prepare(char** argv) {
  TriangleMesh mesh = read_mesh(argv[2]).mesh;
  const int levels = std::stoi(argv[3]);
  for (int i = 0; i < levels; ++i) mesh = split_in_four(mesh);
  write_mesh(argv[4], mesh);
  const std::size_t n = std::stoul(argv[5]);
  const std::uint64_t seed = std::stoull(argv[7]);
  const std::vector<Vector3d> samples = sample_mesh_surface(mesh, n, seed);
  const double diagonal = bounding_box(mesh.vertices.positions).diagonal();
  // The face normal at each sample, through the hierarchy (the sample lies on its triangle).
  const TriangleBvh bvh(mesh);
  PointCloud cloud;
  cloud.positions.resize(samples.size());
  std::mt19937_64 rng(seed + 1);
  std::uniform_real_distribution<double> offset(-0.02 * diagonal, 0.02 * diagonal);
  std::vector<double> offsets(samples.size());
  for (double& o : offsets) o = offset(rng);
  tbb::parallel_for(std::size_t(0), samples.size(), [&](std::size_t i) {
    const ClosestPoint c = bvh.closest(samples[i]);
    const Triangle& t = mesh.triangles[std::size_t(c.triangle)];
    const Vector3d& a = mesh.vertices.positions[std::size_t(t[0])];
    const Vector3d normal = (mesh.vertices.positions[std::size_t(t[1])] - a).cross(mesh.vertices.positions[std::size_t(t[2])] - a).normalized();
    cloud.positions[i] = samples[i] + offsets[i] * normal;
  });
  write_point_cloud(argv[6], cloud);
  fmt::print("{{\"triangles\": {}, \"vertices\": {}, \"points\": {}, \"diagonal\": {}}}\n", mesh.triangles.size(), mesh.vertices.positions.size(),
             cloud.size(), diagonal);
  return 0;
}

int time_mode(char** argv) {
  const TriangleMesh mesh = read_mesh(argv[2]).mesh;
  const std::vector<Vector3d> points = read_point_cloud(argv[3]).cloud.positions;
  const std::string mode = argv[4];
  const double rss_before = bench::peak_rss_mb();
  const auto start = bench::Clock::now();
  const TriangleBvh bvh(mesh);
  const double build = bench::seconds_since(start);
  std::vector<double> d(points.size());
  std::string sign = "unsigned";
  if (mode == "unsigned") {
    const std::vector<double> u = nearest_surface_distances(points, SurfaceView{mesh.vertices.positions, mesh.triangles}, true, 0, 0, &bvh);
    d = u;
  } else if (mode == "signed" || mode == "winding") {
    MeshDistanceParams p;
    p.sign = mode == "winding" ? DistanceSign::WindingNumber : DistanceSign::Auto;
    MeshDistanceResult r = mesh_distances(points, mesh, p, &bvh);
    d = std::move(r.distances);
    sign = distance_sign_names().name(r.sign_used);
  } else {
    fmt::print(stderr, "unknown mode {}\n", mode);
    return 1;
  }
  const double seconds = bench::seconds_since(start);
  std::ofstream(argv[5], std::ios::binary).write(reinterpret_cast<const char*>(d.data()), std::streamsize(d.size() * sizeof(double)));
  fmt::print("{{\"mode\": \"{}\", \"sign\": \"{}\", \"seconds\": {:.4f}, \"build_seconds\": {:.4f}, \"peak_rss_mb\": {:.1f}, "
             "\"rss_before_mb\": {:.1f}, \"points\": {}, \"triangles\": {}}}\n",
             mode, sign, seconds, build, bench::peak_rss_mb(), rss_before, points.size(), mesh.triangles.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string command = argc > 1 ? argv[1] : "";
    if (command == "prepare" && argc == 8) return prepare(argv);
    if (command == "time" && argc == 6) return time_mode(argv);
    fmt::print(stderr,
               "usage: mesh_distance_runner prepare MESH LEVELS OUT_MESH N OUT_POINTS SEED\n"
               "       mesh_distance_runner time MESH POINTS unsigned|signed|winding OUT.bin\n");
    return 1;
  } catch (const pointsurf::Error& e) {
    fmt::print(stderr, "mesh_distance_runner: {}\n", e.what());
    return e.exit_code();
  } catch (const std::exception& e) {
    fmt::print(stderr, "mesh_distance_runner: {}\n", e.what());
    return 2;
  }
}
