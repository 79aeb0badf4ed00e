// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/run_bench.sh.
//   pointsurf_bench sample MESH N OUT.ply [SEED]  area-uniform samples with true (face) normals
//   pointsurf_bench STAGE CLOUD.ply [THREADS]     STAGE: read write knn normals orient
// Prints one JSON line: stage, points, seconds (the stage alone, file reading excluded except
// for "read"), peak_rss_mb (whole process), and the quality figure of the stage.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;
using pointsurf::bench::seconds_since;

using namespace pointsurf;

int sample(const std::string& mesh_path, std::size_t n, const std::string& out, std::uint64_t seed) {
  const TriangleMesh mesh = read_mesh(mesh_path).mesh;
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& f = mesh.triangles[t];
    total += 0.5 * (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]).norm();
    cumulative[t] = total;
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  cloud.positions.reserve(n);
  cloud.normals.reserve(n);
  while (cloud.positions.size() < n) {
    const double r = u(rng) * total;
    const std::size_t t = static_cast<std::size_t>(std::lower_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin());
    const Triangle& f = mesh.triangles[std::min(t, mesh.triangles.size() - 1)];
    const Vector3d &a = mesh.vertices[f[0]], &b = mesh.vertices[f[1]], &c = mesh.vertices[f[2]];
    const Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() == 0.0) continue;
    const double s = std::sqrt(u(rng));
    const double v = u(rng);
    cloud.positions.push_back((1.0 - s) * a + s * (1.0 - v) * b + s * v * c);
    cloud.normals.push_back(normal.normalized());
  }
  write_point_cloud(out, cloud);
  return 0;
}

// Mean unoriented angle (degrees) and the share of normals on the same side as the truth.
std::pair<double, double> normal_errors(const std::vector<Vector3d>& truth, const std::vector<Vector3d>& estimate) {
  double sum = 0.0;
  std::size_t agree = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double c = truth[i].dot(estimate[i]);
    sum += std::acos(std::min(1.0, std::abs(c))) * 180.0 / std::numbers::pi;
    agree += c > 0.0;
  }
  const double n = static_cast<double>(truth.size());
  return {sum / n, static_cast<double>(agree) / n};
}

int run_stage(const std::string& stage, const std::string& path) {
  nlohmann::json out = {{"tool", "pointsurf"}, {"stage", stage}};
  auto t0 = Clock::now();
  PointCloud cloud = read_point_cloud(path).cloud;
  const double read_seconds = seconds_since(t0);
  out["points"] = cloud.size();
  const std::vector<Vector3d> truth = cloud.normals;
  if (stage == "read") {
    out["seconds"] = read_seconds;
  } else if (stage == "write") {
    const std::filesystem::path tmp = std::filesystem::temp_directory_path() / fmt::format("pointsurf_bench_{}.ply", ::getpid());
    t0 = Clock::now();
    write_point_cloud(tmp, cloud);
    out["seconds"] = seconds_since(t0);
    std::filesystem::remove(tmp);
  } else if (stage == "knn") {
    t0 = Clock::now();
    const KdTree tree(cloud.positions);
    const NeighborLists lists = tree.knn_all({}, 30);
    out["seconds"] = seconds_since(t0);
    out["neighbors"] = lists.neighbors.size();
  } else if (stage == "normals") {
    cloud.normals.clear();
    t0 = Clock::now();
    const KdTree tree(cloud.positions);
    NormalParams params;
    params.k = 30;
    estimate_normals(cloud, params, &tree);
    out["seconds"] = seconds_since(t0);
    out["mean_angle_deg"] = normal_errors(truth, cloud.normals).first;
  } else if (stage == "orient") {
    // Orientation alone: start from PCA normals (estimated outside the timed part) with
    // scrambled signs, as Open3D's benchmark does.
    cloud.normals.clear();
    const KdTree tree(cloud.positions);
    NormalParams params;
    params.k = 30;
    estimate_normals(cloud, params, &tree);
    std::mt19937_64 rng(5);
    for (Vector3d& n : cloud.normals)
      if (rng() & 1) n = -n;
    t0 = Clock::now();
    OrientParams orient;
    orient.k = 10;
    orient_normals(cloud, orient, &tree);
    out["seconds"] = seconds_since(t0);
    const double share = normal_errors(truth, cloud.normals).second;
    out["outward_share"] = share;
    out["consistent_share"] = std::max(share, 1.0 - share);
  } else {
    throw UsageError(fmt::format("unknown stage '{}'", stage));
  }
  out["peak_rss_mb"] = peak_rss_mb();
  fmt::print("{}\n", out.dump());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc >= 5 && std::string(argv[1]) == "sample")
      return sample(argv[2], std::stoull(argv[3]), argv[4], argc > 5 ? std::stoull(argv[5]) : 1);
    if (argc >= 3) return run_stage(argv[1], argv[2]);
    fmt::print(stderr, "usage: pointsurf_bench sample MESH N OUT.ply [SEED] | pointsurf_bench read|write|knn|normals|orient CLOUD.ply\n");
    return 1;
  } catch (const pointsurf::Error& e) {
    fmt::print(stderr, "pointsurf_bench: {}\n", e.what());
    return e.exit_code();
  }
}
