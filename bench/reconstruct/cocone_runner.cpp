// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/reconstruct/run_cocone_bench.sh.
//   cocone_runner run CLOUD.ply OUT.ply [drop_normals|keep_normals [cocone|crust [COCONE_ANGLE_DEG [MAX_HOLE_PERIMETER]]]]
//   cocone_runner xyz CLOUD.ply OUT.xyz       positions only, for the CGAL peer
// Reads the cloud (normals dropped when the third argument is "drop_normals", so that the pole
// vectors orient the mesh), runs reconstruct_cocone (default) or reconstruct_crust with default
// parameters (or the given cocone angle and hole-perimeter limit in spacings; 0: no hole filling)
// and writes the mesh.
// Prints one JSON line: seconds (whole reconstruction, file reading excluded), delaunay_seconds,
// peak_rss_mb (whole process, reading included), the stage counts and the mesh topology.
#include <sys/resource.h>

#include <chrono>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/reconstruct/cocone.h"
#include "pointsurf/reconstruct/crust.h"
#include "../bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;

using namespace pointsurf;

int run(const std::string& cloud_path, const std::string& out_path, bool drop_normals, const std::string& method,
        const CoconeParams& params) {
  PointCloud cloud = read_point_cloud(cloud_path).cloud;
  if (drop_normals) cloud.normals.clear();
  CrustStats stats;  // a DelaunaySurfaceStats with the Crust's counts (zero for the cocone)
  const Clock::time_point start = Clock::now();
  // Wall time at each progress report: the stage boundaries (0.45 Delaunay, 0.5 circumcentres,
  // 0.55 poles, 0.7 cocone test, 0.8 pruning, 0.9 walk, 1 peeling, holes, orientation, topology).
  nlohmann::json stages = nlohmann::json::array();
  const auto report = [&](double fraction) {
    stages.push_back({fraction, std::chrono::duration<double>(Clock::now() - start).count()});
    return true;
  };
  ReconstructionResult result;
  if (method == "crust") {
    CrustParams crust;
    static_cast<DelaunaySurfaceParams&>(crust) = params;
    result = reconstruct_crust(cloud, crust, report, &stats);
  } else {
    CoconeStats cocone;
    result = reconstruct_cocone(cloud, params, report, &cocone);
    static_cast<DelaunaySurfaceStats&>(stats) = cocone;
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
  const double rss = peak_rss_mb();
  write_mesh(out_path, result.mesh);
  const MeshTopology& t = result.topology;
  nlohmann::json out;
  out["tool"] = "pointsurf_" + method;
  out["points"] = cloud.size();
  out["seconds"] = seconds;
  out["delaunay_seconds"] = stats.seconds_delaunay;
  out["stage_seconds"] = stages;
  out["peak_rss_mb"] = rss;
  out["mean_spacing"] = result.mean_spacing;
  out["delaunay_cells"] = stats.delaunay_cells;
  out["hull_points"] = stats.hull_points;
  out["candidate_triangles"] = stats.candidate_triangles;
  out["normal_filtered"] = stats.normal_filtered;
  out["pruned"] = stats.pruned;
  out["walk_dropped"] = stats.walk_dropped;
  out["rim_peeled"] = stats.rim_peeled;
  out["holes_filled"] = stats.holes_filled;
  out["cocone_angle_deg"] = params.cocone_angle_deg;
  out["max_hole_perimeter_in_spacings"] = params.max_hole_perimeter_in_spacings;
  out["poles"] = stats.poles;
  out["second_delaunay_cells"] = stats.second_delaunay_cells;
  out["open_pieces"] = stats.open_pieces;
  out["closed_pieces"] = stats.closed_pieces;
  out["triangles"] = t.triangles;
  out["unused_points"] = result.unused_points;
  out["boundary_edges"] = t.boundary_edges;
  out["non_manifold_edges"] = t.non_manifold_edges;
  out["non_manifold_vertices"] = t.non_manifold_vertices;
  out["inconsistent_edges"] = t.inconsistent_edges;
  out["components"] = t.components;
  out["euler_characteristic"] = t.euler_characteristic;
  fmt::print("{}\n", out.dump());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "run" && argc >= 4 && argc <= 8) {
      CoconeParams params;
      const std::string method = argc >= 6 ? argv[5] : "cocone";
      if (method != "cocone" && method != "crust") throw UsageError("method: expected cocone or crust, got " + method);
      if (argc >= 7) params.cocone_angle_deg = std::stod(argv[6]);
      if (argc >= 8) params.max_hole_perimeter_in_spacings = std::stod(argv[7]);
      return run(argv[2], argv[3], argc >= 5 && std::string(argv[4]) == "drop_normals", method, params);
    }
    if (mode == "xyz" && argc == 4) {
      PointCloud cloud = read_point_cloud(argv[2]).cloud;
      PointCloud positions;
      positions.positions = std::move(cloud.positions);
      write_point_cloud(argv[3], positions);
      return 0;
    }
    fmt::print(stderr, "usage: cocone_runner run CLOUD.ply OUT.ply [drop_normals|keep_normals [cocone|crust [COCONE_ANGLE_DEG [MAX_HOLE_PERIMETER]]]] | xyz CLOUD.ply OUT.xyz\n");
    return 1;
  } catch (const Error& e) {
    fmt::print(stderr, "cocone_runner: {}\n", e.what());
    return e.exit_code();
  }
}
