// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/features/run_features_bench.sh: times detect_feature_points and scores
// it against sharp edges known by construction.
//   features_runner SHAPE N NOISE REPEATS [OUT.ply]
// SHAPE: cube, cad (the samplers of tests/support/features_shapes.h) or a mesh file (OFF, ...):
// points sampled area-uniformly on its triangles (seed 1), sharp edges = mesh edges (vertices
// welded by position) whose faces turn by at least 30 degrees (issue 13's truth). Truth: points
// within 0.5 clean mean spacings of a sharp edge; a labelled point is right within 1.5.
// NOISE: Gaussian sigma in mean spacings. Prints one JSON line per variant (robust normals, the
// default, timed with the kd-tree built inside the timer; input PCA normals and the
// surface-variation threshold alone, with a prebuilt tree), with recall per 30-degree bin of
// the nearest edge's turn for meshes. With OUT.ply it also writes the noisy cloud with a field
// "truth" and OUT.ply.truth.txt / OUT.ply.dist.txt (labels, distances) for the peer scripts.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <sys/resource.h>

#include "../../tests/support/features_shapes.cpp"
#include "pointsurf/features/feature_points.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "../bench_util.h"

namespace {

using pointsurf::bench::peak_rss_mb;

using namespace pointsurf;
constexpr double kMeshSharpDeg = 30.0;
constexpr double kTruthSpacings = 0.5;      // a point within this of a sharp edge must be found (issue 13)
constexpr double kToleranceSpacings = 1.5;  // a labelled point within this is correct

template <class F>
double seconds(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: features_runner cube|cad|MESH N NOISE_SPACINGS REPEATS [OUT.ply]\n");
    return 1;
  }
  const std::string shape_name = argv[1];
  const std::size_t n = std::stoull(argv[2]);
  const double noise = std::stod(argv[3]);
  const int repeats = std::stoi(argv[4]);
  test::FeatureShape shape = shape_name == "cube" ? test::sample_cube_features(n)
                             : shape_name == "cad" ? test::sample_cad_part(n)
                                                   : test::sample_mesh_features(read_mesh(shape_name).mesh, n, kMeshSharpDeg, 1);
  const double clean_spacing = mean_spacing(shape.cloud.positions);
  test::add_feature_noise(shape, noise * clean_spacing);
  shape.cloud.normals.clear();
  const double spacing = mean_spacing(shape.cloud.positions);
  const std::string label = shape_name.substr(shape_name.find_last_of('/') + 1);

  auto emit = [&](const std::string& variant, const std::vector<double>& labels, double time, const FeatureResult& r) {
    const test::FeatureScore s = test::score_features(labels, shape.edge_distance, kTruthSpacings * clean_spacing,
                                                      kToleranceSpacings * clean_spacing);
    nlohmann::json j = {{"tool", "pointsurf"},   {"variant", variant},      {"shape", label},
                        {"points", n},           {"noise_spacings", noise}, {"seconds", time},
                        {"peak_rss_mb", peak_rss_mb()}, {"precision", s.precision}, {"recall", s.recall},
                        {"labelled", s.labelled}, {"truth", s.truth},       {"candidates", r.candidates},
                        {"edges", r.edges},      {"corners", r.corners},    {"threshold", r.variation_threshold_used},
                        {"mean_spacing", spacing}};
    // Recall by the turn angle of the nearest sharp edge (mesh inputs), in 30-degree bins.
    if (!shape.edge_turn_deg.empty()) {
      for (int lo = 30; lo < 180; lo += 30) {
        std::size_t truth = 0, found = 0;
        for (std::size_t i = 0; i < n; ++i)
          if (shape.edge_distance[i] <= kTruthSpacings * clean_spacing && shape.edge_turn_deg[i] >= lo && shape.edge_turn_deg[i] < lo + 30)
            ++truth, found += labels[i] != 0.0;
        j[fmt::format("truth_turn_{}", lo)] = truth;
        j[fmt::format("recall_turn_{}", lo)] = truth == 0 ? 0.0 : double(found) / double(truth);
      }
    }
    fmt::print("{}\n", j.dump());
  };

  // Robust normals (the default), timed over REPEATS runs with the kd-tree built inside the timer
  // (as Open3D's search structure is inside its own).
  std::vector<double> times;
  PointCloud cloud = shape.cloud;
  FeatureResult robust;
  for (int r = 0; r < repeats; ++r) times.push_back(seconds([&] { robust = detect_feature_points(cloud); }));
  const KdTree tree(shape.cloud.positions);
  const std::vector<double> robust_labels = cloud.fields.find("feature")->values;
  emit("robust", robust_labels, median(times), robust);

  // The cloud's PCA normals (k = 16) as the clustering normals.
  PointCloud with_normals = shape.cloud;
  estimate_normals(with_normals, {.k = 30, .keep_variation = false}, &tree);
  times.clear();
  FeatureResult input;
  for (int r = 0; r < repeats; ++r)
    times.push_back(seconds([&] { input = detect_feature_points(with_normals, {.normals = FeatureNormals::Input}, &tree); }));
  emit("input_pca_normals", with_normals.fields.find("feature")->values, median(times), input);

  // The candidate step alone (surface variation above the same threshold): what a
  // curvature-threshold detector in Open3D or PCL gives.
  PointCloud proxy = shape.cloud;
  times.clear();
  for (int r = 0; r < repeats; ++r)
    times.push_back(seconds([&] { estimate_normals(proxy, {.k = 30, .keep_variation = true}, &tree); }));
  std::vector<double> proxy_labels = proxy.fields.find("variation")->values;
  for (double& s : proxy_labels) s = s > robust.variation_threshold_used ? 1.0 : 0.0;
  emit("variation_only", proxy_labels, median(times), robust);

  if (argc > 5) {
    PointCloud out = shape.cloud;
    ScalarField& truth = out.fields.add("truth", n, ScalarType::UInt8);
    std::string text;
    for (std::size_t i = 0; i < n; ++i) {
      truth.values[i] = shape.edge_distance[i] <= kTruthSpacings * clean_spacing ? 1.0 : 0.0;
      text += truth.values[i] != 0.0 ? "1\n" : "0\n";
    }
    write_point_cloud(argv[5], out);
    std::FILE* f = std::fopen((std::string(argv[5]) + ".truth.txt").c_str(), "w");
    if (f == nullptr) return 2;
    std::fputs(text.c_str(), f);
    std::fclose(f);
    // Distances too, so the peer script scores with the same band as above.
    std::FILE* d = std::fopen((std::string(argv[5]) + ".dist.txt").c_str(), "w");
    if (d == nullptr) return 2;
    for (double e : shape.edge_distance) std::fprintf(d, "%.6g\n", e / clean_spacing);
    std::fclose(d);
  }
  return 0;
}
