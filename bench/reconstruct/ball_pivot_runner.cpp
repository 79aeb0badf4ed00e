// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/reconstruct/run_ball_pivot_bench.sh.
//   ball_pivot_runner spacing CLOUD.ply                  prints the mean spacing
//   ball_pivot_runner noisify CLOUD.ply SIGMA OUT.ply     Gaussian noise of SIGMA (cloud units,
//                                                        seed 7) on the positions; normals kept
//   ball_pivot_runner run CLOUD.ply R1,R2,.. OUT.ply     ball pivoting with these radii (cloud
//                                                        units); writes the mesh
// `run` prints one JSON line: seconds (kd-tree build + ball pivoting, file reading excluded),
// peak_rss_mb (whole process, reading included), triangles and the mesh topology.
#include <sys/resource.h>

#include <chrono>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/reconstruct/ball_pivot.h"
#include "pointsurf/spatial/kd_tree.h"
#include "../bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;
using pointsurf::bench::seconds_since;

using namespace pointsurf;

std::vector<double> parse_list(const std::string& text) {
  std::vector<double> values;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) values.push_back(std::stod(item));
  return values;
}

int run(const std::string& cloud_path, const std::string& radii, const std::string& out_path) {
  const PointCloud cloud = read_point_cloud(cloud_path).cloud;
  BallPivotParams params;
  params.radii = parse_list(radii);
  const Clock::time_point start = Clock::now();
  const KdTree tree(cloud.positions);
  const double tree_seconds = seconds_since(start);
  const ReconstructionResult result = reconstruct_ball_pivoting(cloud, params, &tree);
  const double seconds = seconds_since(start);
  const double rss = peak_rss_mb();
  write_mesh(out_path, result.mesh);
  const MeshTopology& t = result.topology;
  nlohmann::json out;
  out["tool"] = "pointsurf";
  out["points"] = cloud.size();
  out["seconds"] = seconds;
  out["tree_seconds"] = tree_seconds;
  out["peak_rss_mb"] = rss;
  out["triangles"] = t.triangles;
  out["unused_points"] = result.unused_points;
  out["boundary_edges"] = t.boundary_edges;
  out["non_manifold_edges"] = t.non_manifold_edges;
  out["non_manifold_vertices"] = t.non_manifold_vertices;
  out["inconsistent_edges"] = t.inconsistent_edges;
  out["components"] = t.components;
  fmt::print("{}\n", out.dump());
  return 0;
}

int noisify(const std::string& cloud_path, double sigma, const std::string& out_path) {
  PointCloud cloud = read_point_cloud(cloud_path).cloud;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, sigma);
  for (Vector3d& p : cloud.positions) p += Vector3d(g(rng), g(rng), g(rng));
  write_point_cloud(out_path, cloud);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "spacing" && argc == 3) {
      fmt::print("{:.17g}\n", mean_spacing(read_point_cloud(argv[2]).cloud.positions));
      return 0;
    }
    if (mode == "noisify" && argc == 5) return noisify(argv[2], std::stod(argv[3]), argv[4]);
    if (mode == "run" && argc == 5) return run(argv[2], argv[3], argv[4]);
    fmt::print(stderr,
               "usage: ball_pivot_runner spacing CLOUD.ply | noisify CLOUD.ply SIGMA OUT.ply | run CLOUD.ply R1,R2,.. OUT.ply\n");
    return 1;
  } catch (const Error& e) {
    fmt::print(stderr, "ball_pivot_runner: {}\n", e.what());
    return e.exit_code();
  }
}
