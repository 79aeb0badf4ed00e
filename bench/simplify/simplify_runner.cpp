// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/simplify/run_simplify_bench.sh. Prints one JSON line per call.
//   simplify_runner grid CLOUD CELL [OUT.ply]      voxel grid (centroid) with the given cell
//   simplify_runner regional CLOUD RATIO           kd-tree + normals/variation + regional
//   simplify_runner METHOD CLOUD RATIO [OUT.ply]   METHOD: random curvature regional
//                                                  curvature-distance lfs grid-ratio
//   simplify_runner pipeline CLOUD RATIO [REPEATS] statistical outlier removal then regional,
//                                                  per stage (medians)
//   simplify_runner compare A B                    nearest distances between two clouds
//   simplify_runner quality FULL SIMPLIFIED        Chamfer / Hausdorff of SIMPLIFIED to FULL
//   simplify_runner edges N RATIO                  share of a cube's sharp-edge points kept
//                                                  by every method at the same output size
// Times are the library stages alone (file reading excluded); peak_rss_mb is the process'.
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/simplify/simplify.h"
#include "pointsurf/spatial/kd_tree.h"
#include "../bench_util.h"

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;
using pointsurf::bench::seconds_since;

using namespace pointsurf;

struct Distances {
  double mean_ab = 0, max_ab = 0, mean_ba = 0, max_ba = 0;
};

Distances distances(const std::vector<Vector3d>& a, const std::vector<Vector3d>& b) {
  const SurfaceDistanceResult r = surface_distance(SurfaceView{a, {}}, SurfaceView{b, {}});
  return {r.a_to_b.mean, r.a_to_b.max, r.b_to_a.mean, r.b_to_a.max};
}

nlohmann::json quality(const PointCloud& full, const PointCloud& simplified) {
  const Distances d = distances(full.positions, simplified.positions);
  const double spacing = mean_spacing(full.positions);
  return {{"chamfer", 0.5 * (d.mean_ab + d.mean_ba)},
          {"hausdorff", std::max(d.max_ab, d.max_ba)},
          {"chamfer_in_spacings", 0.5 * (d.mean_ab + d.mean_ba) / spacing},
          {"hausdorff_in_spacings", std::max(d.max_ab, d.max_ba) / spacing}};
}

PointCloud bare(PointCloud cloud) {
  cloud.normals.clear();
  cloud.fields = {};
  return cloud;
}

SimplifyResult run_method(const std::string& method, const PointCloud& cloud, const SimplifyTarget& target, const KdTree* tree) {
  if (method == "grid-ratio") return simplify_grid(cloud, {target, GridMode::Nearest});
  if (method == "random") return simplify_random(cloud, {target});
  if (method == "curvature") return simplify_curvature(cloud, {target}, tree);
  if (method == "regional") return simplify_regional(cloud, {target}, tree);
  if (method == "curvature-distance") return simplify_curvature_distance(cloud, {target}, tree);
  if (method == "lfs") return resample_lfs(cloud, {target}, tree);
  throw std::runtime_error("unknown method " + method);
}

// n points area-uniformly on the cube [-1, 1]^3 (seeded), positions only.
PointCloud cube(std::size_t n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> face(0, 5);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const int f = face(rng);
    Vector3d p;
    p[f / 2] = f % 2 == 0 ? 1.0 : -1.0;
    p[(f / 2 + 1) % 3] = u(rng);
    p[(f / 2 + 2) % 3] = u(rng);
    c.positions.push_back(p);
  }
  return c;
}

int run(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: simplify_runner grid|METHOD|pipeline|compare|quality|edges ...\n");
    return 1;
  }
  const std::string what = argv[1];
  nlohmann::json out = {{"tool", "pointsurf"}, {"stage", what}};
  if (what == "pipeline") {
    // The paper's preprocessing: statistical outlier removal, then regional simplification,
    // library time only (the file is read first). Medians over the repeats.
    const PointCloud cloud = bare(read_point_cloud(argv[2]).cloud);
    SimplifyTarget target;
    target.ratio = std::stod(argv[3]);
    const int repeats = argc > 4 ? std::stoi(argv[4]) : 5;
    std::vector<double> tree_s, sor_s, regional_s, total_s;
    std::size_t kept = 0, output = 0;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = Clock::now();
      const KdTree tree(cloud.positions);
      tree_s.push_back(seconds_since(t0));
      // One kNN pass gives normals, variation and the outlier statistic (k = 20, the
      // statistical default); the regional step builds one tree over the cleaned cloud (for its
      // boundary test and its thinning) and reuses the normals, variation and spacing.
      auto t1 = Clock::now();
      PointCloud work = cloud;
      NormalParams normals;
      normals.k = StatisticalOutlierParams{}.k;
      normals.keep_mean_distance = true;
      estimate_normals(work, normals, &tree);
      const OutlierResult sor =
          statistical_outliers_from_distances(work.fields.find("mean_distance")->values, StatisticalOutlierParams{}.std_ratio);
      const PointCloud clean = keep_points(work, sor.kept);
      const double spacing = mean_spacing(tree);
      sor_s.push_back(seconds_since(t1));
      t1 = Clock::now();
      RegionalParams params;
      params.target = target;
      params.spacing = spacing;
      const SimplifyResult res = simplify_regional(clean, params);
      regional_s.push_back(seconds_since(t1));
      total_s.push_back(seconds_since(t0));
      kept = clean.size();
      output = res.cloud.size();
    }
    const auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    out.update({{"points", cloud.size()}, {"kept_after_sor", kept}, {"output_points", output}, {"repeats", repeats},
                {"kdtree_seconds", median(tree_s)}, {"normals_sor_spacing_seconds", median(sor_s)}, {"regional_seconds", median(regional_s)},
                {"seconds", median(total_s)}});
  } else if (what == "compare") {
    const PointCloud a = read_point_cloud(argv[2]).cloud, b = read_point_cloud(argv[3]).cloud;
    const Distances d = distances(a.positions, b.positions);
    out.update({{"points_a", a.size()}, {"points_b", b.size()}, {"max_a_to_b", d.max_ab}, {"max_b_to_a", d.max_ba}});
  } else if (what == "quality") {
    const PointCloud full = read_point_cloud(argv[2]).cloud, simplified = read_point_cloud(argv[3]).cloud;
    out.update(quality(full, simplified));
    out["points"] = full.size();
    out["output_points"] = simplified.size();
  } else if (what == "edges") {
    const std::size_t n = std::stoul(argv[2]);
    SimplifyTarget target;
    target.ratio = std::stod(argv[3]);
    const PointCloud c = cube(n);
    const KdTree tree(c.positions);
    const double spacing = mean_spacing(tree);
    std::size_t total = 0;
    std::vector<char> edge(n);
    for (std::size_t i = 0; i < n; ++i) {
      int on = 0;
      for (int a = 0; a < 3; ++a) on += 1.0 - std::abs(c.positions[i][a]) < 0.5 * spacing;
      edge[i] = on >= 2;
      total += edge[i];
    }
    out["points"] = n;
    out["edge_points"] = total;
    out["edge_tolerance_in_spacings"] = 0.5;
    for (const std::string method : {"grid-ratio", "random", "curvature", "regional", "curvature-distance", "lfs"}) {
      const auto t0 = Clock::now();
      const SimplifyResult r = run_method(method, c, target, &tree);
      const double seconds = seconds_since(t0);
      std::size_t kept = 0;
      for (std::size_t s : r.source_index) kept += edge[s];
      nlohmann::json m = quality(c, r.cloud);
      m["output_points"] = r.cloud.size();
      m["edge_share_kept"] = double(kept) / double(total);
      m["seconds"] = seconds;
      out["methods"][method] = m;
    }
  } else {
    PointCloud cloud = read_point_cloud(argv[2]).cloud;
    out["points"] = cloud.size();
    const std::string path = argc > 4 ? argv[4] : "";
    SimplifyResult r;
    if (what == "grid") {
      cloud.normals.clear();  // positions only, as open3d_simplify.py gives Open3D
      GridParams p;
      p.target.cell = std::stod(argv[3]);
      const auto t0 = Clock::now();
      r = simplify_grid(cloud, p);
      out["seconds"] = seconds_since(t0);
    } else {
      cloud = bare(std::move(cloud));  // a raw scan: the methods estimate what they need
      SimplifyTarget target;
      target.ratio = std::stod(argv[3]);
      const auto t0 = Clock::now();
      const KdTree tree(cloud.positions);
      const double tree_seconds = seconds_since(t0);
      r = run_method(what, cloud, target, &tree);
      out["seconds"] = seconds_since(t0);
      out["kdtree_seconds"] = tree_seconds;
    }
    out["peak_rss_mb"] = peak_rss_mb();
    out["output_points"] = r.cloud.size();
    out["length_used"] = r.length_used;
    out["feature_points"] = r.feature_points;
    out["added_points"] = r.added_points;
    out.update(quality(cloud, r.cloud));
    if (!path.empty()) write_point_cloud(path, r.cloud);
  }
  std::printf("%s\n", out.dump().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "simplify_runner: %s\n", e.what());
    return 1;
  }
}
