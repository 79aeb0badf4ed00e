// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/run_bench.sh.
//   pointsurf_bench sample MESH N OUT.ply [SEED]  area-uniform samples with true (face) normals
//   pointsurf_bench STAGE CLOUD.ply   STAGE: baseline read write knn knn_input normals orient
// Prints one JSON line: stage, points, seconds (wall) and cpu_seconds (user + system, all
// threads) of the stage alone (file reading excluded except for "read"), peak_rss_mb (whole
// process), and the quality figure of the stage. "baseline" reads nothing (the process's own
// memory); "knn" queries in the tree's spatial order, "knn_input" in the file's order;
// "normals" and "orient" build their own search structures inside the timed part.
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

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::cpu_seconds;
using pointsurf::bench::peak_rss_mb;
using pointsurf::bench::seconds_since;

using namespace pointsurf;

int sample(const std::string& mesh_path, std::size_t n, const std::string& out, std::uint64_t seed) {
  const TriangleMesh mesh = read_mesh(mesh_path).mesh;
  std::vector<double> cumulative(mesh.triangles.size());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle& f = mesh.triangles[t];
    total += 0.5 * (mesh.vertices.positions[f[1]] - mesh.vertices.positions[f[0]]).cross(mesh.vertices.positions[f[2]] - mesh.vertices.positions[f[0]]).norm();
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
    const Vector3d &a = mesh.vertices.positions[f[0]], &b = mesh.vertices.positions[f[1]], &c = mesh.vertices.positions[f[2]];
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
  if (stage == "baseline") {
    out["points"] = 0;
    out["peak_rss_mb"] = peak_rss_mb();
    fmt::print("{}\n", out.dump());
    return 0;
  }
  auto t0 = Clock::now();
  double c0 = cpu_seconds();
  PointCloud cloud = read_point_cloud(path).cloud;
  const double read_seconds = seconds_since(t0);
  const double read_cpu = cpu_seconds() - c0;
  out["points"] = cloud.size();
  const std::vector<Vector3d> truth = cloud.normals;
  const auto start = [&] {
    t0 = Clock::now();
    c0 = cpu_seconds();
  };
  const auto stop = [&] {
    out["seconds"] = seconds_since(t0);
    out["cpu_seconds"] = cpu_seconds() - c0;
  };
  if (stage == "read") {
    out["seconds"] = read_seconds;
    out["cpu_seconds"] = read_cpu;
  } else if (stage == "write") {
    const std::filesystem::path tmp = std::filesystem::temp_directory_path() / fmt::format("pointsurf_bench_{}.ply", ::getpid());
    start();
    write_point_cloud(tmp, cloud);
    stop();
    std::filesystem::remove(tmp);
  } else if (stage == "knn" || stage == "knn_input") {
    start();
    const KdTree tree(cloud.positions);
    const NeighborLists lists = tree.knn_all(stage == "knn" ? std::span<const Vector3d>{} : std::span<const Vector3d>(cloud.positions), 30);
    stop();
    out["neighbors"] = lists.neighbors.size();
  } else if (stage == "normals") {
    cloud.normals.clear();
    start();
    NormalParams params;
    params.k = 30;
    estimate_normals(cloud, params);
    stop();
    out["mean_angle_deg"] = normal_errors(truth, cloud.normals).first;
  } else if (stage == "orient") {
    // Orientation alone: start from PCA normals (estimated outside the timed part) with
    // scrambled signs, as Open3D's benchmark does. The kd-tree is built inside the timed part,
    // as Open3D builds its Delaunay and kd-tree inside its call.
    cloud.normals.clear();
    NormalParams params;
    params.k = 30;
    estimate_normals(cloud, params);
    std::mt19937_64 rng(5);
    for (Vector3d& n : cloud.normals)
      if (rng() & 1) n = -n;
    start();
    OrientParams orient;
    orient.k = 10;
    orient_normals(cloud, orient);
    stop();
    const double share = normal_errors(truth, cloud.normals).second;
    out["outward_share"] = share;
    out["consistent_share"] = std::max(share, 1.0 - share);
  } else if (stage == "radius_outliers" || stage == "radius_outliers_tree") {
    // Radius outliers (4 neighbours within 4 mean spacings), kd-tree and spacing inside the
    // timed part: the library call (voxel grid), or the kd-tree's hybrid query per point.
    start();
    const KdTree tree(cloud.positions);
    RadiusOutlierParams params;
    params.min_neighbours = 4;
    params.radius = Length::spacings(4.0);
    std::size_t kept = 0;
    if (stage == "radius_outliers") {
      kept = remove_radius_outliers(cloud, params, &tree).kept.size();
    } else {
      const double radius = 4.0 * mean_spacing(tree);
      std::vector<std::uint8_t> keep(cloud.size());
      tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<Neighbor>& nb = buffers.local();
        for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
          const std::uint32_t i = tree.spatial_order()[pos];
          tree.hybrid(cloud.positions[i], 5, radius, nb);
          keep[i] = nb.size() >= 5;
        }
      });
      kept = static_cast<std::size_t>(std::count(keep.begin(), keep.end(), std::uint8_t(1)));
    }
    stop();
    out["kept"] = kept;
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
    if (argc >= 2 && std::string(argv[1]) == "baseline") return run_stage(argv[1], "");
    if (argc >= 3) return run_stage(argv[1], argv[2]);
    fmt::print(stderr, "usage: pointsurf_bench sample MESH N OUT.ply [SEED] | pointsurf_bench baseline | pointsurf_bench read|write|knn|knn_input|normals|orient CLOUD.ply\n");
    return 1;
  } catch (const pointsurf::Error& e) {
    fmt::print(stderr, "pointsurf_bench: {}\n", e.what());
    return e.exit_code();
  }
}
