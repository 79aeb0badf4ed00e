// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/features/run_features_bench.sh: times detect_feature_points and scores
// it against sharp edges known by construction.
//   features_runner SHAPE N NOISE REPEATS [OUT.ply]
// SHAPE: cube, cad (the samplers of tests/support/features_shapes.h) or a mesh file (OFF, ...):
// points sampled on its triangles, sharp edges = mesh edges whose faces turn by more than
// MESH_SHARP_DEG (30) degrees. NOISE: Gaussian sigma in mean spacings. Prints one JSON line per
// variant (robust normals, input PCA normals, the surface-variation threshold alone). With
// OUT.ply it also writes the noisy cloud with a field "truth" (1 within one spacing of a sharp
// edge) and OUT.ply.truth.txt (the same labels, one per line) for the peer scripts.
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
constexpr double kTruthSpacings = 1.0;      // a point within this of a sharp edge must be found
constexpr double kToleranceSpacings = 1.5;  // a labelled point within this is correct

// Samples a mesh and gives each sample its distance to the nearest sharp mesh edge, measured
// to points laid along the sharp edges every 0.05 mean spacings (exact to within 0.025 spacings).
test::FeatureShape sample_mesh(const std::string& path, std::size_t n, std::uint64_t seed) {
  const TriangleMesh mesh = read_mesh(path).mesh;
  const auto& v = mesh.vertices;
  std::vector<double> areas;
  std::vector<Vector3d> face_normals;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d c = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    areas.push_back(0.5 * c.norm());
    face_normals.push_back(c.norm() > 0.0 ? Vector3d(c.normalized()) : Vector3d::Zero());
  }
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  test::FeatureShape shape;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t f = pick(rng);
    double s = u(rng), t = u(rng);
    if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
    const Triangle& tri = mesh.triangles[f];
    shape.cloud.positions.push_back(v[tri[0]] + s * (v[tri[1]] - v[tri[0]]) + t * (v[tri[2]] - v[tri[0]]));
    shape.cloud.normals.push_back(face_normals[f]);
  }
  const double spacing = mean_spacing(shape.cloud.positions);
  std::map<std::pair<int, int>, std::vector<std::size_t>> edge_faces;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int a = mesh.triangles[f][e], b = mesh.triangles[f][(e + 1) % 3];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  const double cos_sharp = std::cos(kMeshSharpDeg * std::numbers::pi / 180.0);
  std::vector<Vector3d> edge_points;
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() != 2 || face_normals[faces[0]].dot(face_normals[faces[1]]) > cos_sharp) continue;
    const Vector3d a = v[edge.first], b = v[edge.second];
    const int steps = std::max(1, int(std::ceil((b - a).norm() / (0.05 * spacing))));
    for (int k = 0; k <= steps; ++k) edge_points.push_back(a + (b - a) * (double(k) / steps));
  }
  if (edge_points.empty()) edge_points.push_back(Vector3d::Constant(1e300));
  const KdTree edges(edge_points);
  std::vector<Neighbor> nb;
  for (const Vector3d& p : shape.cloud.positions) {
    edges.knn(p, 1, nb);
    shape.edge_distance.push_back(std::sqrt(nb[0].squared_distance));
    shape.corner_distance.push_back(1e300);
  }
  return shape;
}

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
                                                   : sample_mesh(shape_name, n, 1);
  const double clean_spacing = mean_spacing(shape.cloud.positions);
  test::add_feature_noise(shape, noise * clean_spacing);
  shape.cloud.normals.clear();
  const KdTree tree(shape.cloud.positions);
  const double spacing = mean_spacing(tree);
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
    fmt::print("{}\n", j.dump());
  };

  // Robust normals (the default), timed over REPEATS runs with the tree reused as the CLI does.
  std::vector<double> times;
  PointCloud cloud = shape.cloud;
  FeatureResult robust;
  for (int r = 0; r < repeats; ++r) times.push_back(seconds([&] { robust = detect_feature_points(cloud, {}, &tree); }));
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
