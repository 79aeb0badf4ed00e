// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/shape/run_shape_bench.sh.
//   shape_runner sphere N RADIUS OUT.ply          seeded sphere sample with exact outward normals
//   shape_runner dump IN.ply OUT.bin              uint64 N + N × (x y z nx ny nz) float64 for the CGAL peer
//   shape_runner curvature IN.ply K DEGREE THREADS REPEATS OUT.bin
//       times the kd-tree and estimate_curvature (REPEATS runs, THREADS 0 = all cores), writes
//       N × (k1 k2) float64 of the last run and prints one JSON line.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/global_control.h>
#include <tbb/info.h>

#include "pointsurf/io/io.h"
#include "pointsurf/shape/curvature.h"
#include "pointsurf/spatial/kd_tree.h"

using namespace pointsurf;

namespace {

// CPU time of the process (all threads), seconds: the fairer figure on a loaded machine.
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

int make_sphere(std::size_t n, double radius, const std::string& out) {
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud cloud;
  while (cloud.size() < n) {
    Vector3d v(g(rng), g(rng), g(rng));
    if (v.norm() < 1e-12) continue;
    v.normalize();
    cloud.positions.push_back(radius * v);
    cloud.normals.push_back(v);
  }
  write_point_cloud(out, cloud);
  return 0;
}

int dump(const std::string& in, const std::string& out) {
  const PointCloud cloud = read_point_cloud(in).cloud;
  if (!cloud.has_normals()) {
    std::cerr << in << ": no normals\n";
    return 2;
  }
  std::ofstream o(out, std::ios::binary);
  const std::uint64_t n = cloud.size();
  o.write(reinterpret_cast<const char*>(&n), sizeof n);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double v[6] = {cloud.positions[i].x(), cloud.positions[i].y(), cloud.positions[i].z(),
                         cloud.normals[i].x(),   cloud.normals[i].y(),   cloud.normals[i].z()};
    o.write(reinterpret_cast<const char*>(v), sizeof v);
  }
  return o ? 0 : 3;
}

int curvature(const std::string& in, int k, int degree, int threads, int repeats, const std::string& out) {
  const int used_threads = threads > 0 ? threads : tbb::info::default_concurrency();
  tbb::global_control control(tbb::global_control::max_allowed_parallelism, std::size_t(used_threads));
  PointCloud cloud = read_point_cloud(in).cloud;
  nlohmann::json tree_seconds = nlohmann::json::array(), curvature_seconds = nlohmann::json::array();
  nlohmann::json curvature_cpu = nlohmann::json::array();
  CurvatureResult result;
  for (int r = 0; r < repeats; ++r) {
    auto t0 = std::chrono::steady_clock::now();
    const KdTree tree(cloud.positions);
    tree_seconds.push_back(seconds_since(t0));
    t0 = std::chrono::steady_clock::now();
    const double c0 = cpu_seconds();
    result = estimate_curvature(cloud, {.degree = degree, .k = k}, &tree);
    curvature_seconds.push_back(seconds_since(t0));
    curvature_cpu.push_back(cpu_seconds() - c0);
  }
  const std::vector<double>& k1 = cloud.fields.find("k1")->values;
  const std::vector<double>& k2 = cloud.fields.find("k2")->values;
  std::ofstream o(out, std::ios::binary);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double v[2] = {k1[i], k2[i]};
    o.write(reinterpret_cast<const char*>(v), sizeof v);
  }
  nlohmann::json types = nlohmann::json::object();
  for (int t = 0; t < kSurfaceTypeCount; ++t) types[surface_type_name(static_cast<SurfaceType>(t))] = result.type_counts[std::size_t(t)];
  const nlohmann::json line = {{"tool", "pointsurf"},          {"points", cloud.size()},
                               {"k", k},                       {"degree", degree},
                               {"threads", used_threads},      {"tree_seconds", tree_seconds},
                               {"curvature_seconds", curvature_seconds}, {"curvature_cpu_seconds", curvature_cpu},
                               {"degenerate", result.degenerate},
                               {"zero_curvature", result.zero_curvature}, {"surface_types", types}};
  std::cout << line.dump() << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> a(argv + 1, argv + argc);
    if (a.size() == 4 && a[0] == "sphere") return make_sphere(std::stoul(a[1]), std::stod(a[2]), a[3]);
    if (a.size() == 3 && a[0] == "dump") return dump(a[1], a[2]);
    if (a.size() == 7 && a[0] == "curvature")
      return curvature(a[1], std::stoi(a[2]), std::stoi(a[3]), std::stoi(a[4]), std::stoi(a[5]), a[6]);
    std::cerr << "usage: shape_runner sphere N RADIUS OUT.ply | dump IN.ply OUT.bin | "
                 "curvature IN.ply K DEGREE THREADS REPEATS OUT.bin\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "shape_runner: " << e.what() << "\n";
    return 3;
  }
}
