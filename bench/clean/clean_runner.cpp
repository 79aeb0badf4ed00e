// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/clean/run_clean_bench.sh: times the cleaning stages on a file, makes
// synthetic noisy CAD-like shapes with known surfaces and creases, and scores results (its own
// and the peers') against those surfaces. Prints one JSON object per line.
//   clean_runner sor IN K STD_RATIO KEPT_OUT          statistical outliers, kept indices to a file
//   clean_runner radius IN MIN_NEIGHBOURS RADIUS KEPT_OUT
//   clean_runner smooth bilateral|trilateral IN OUT   denoise (IN needs normals)
//   clean_runner synth SHAPE N NOISE_IN_SPACINGS OUT [SEED]   noisy shape, PCA normals
//   clean_runner score SHAPE FILE                     RMS distance to the true surface: all,
//                                                     near creases (<= 2 spacings), flat (> 5)
// SHAPE: sphere, cube, part, or a mesh file (sampled area-uniformly; creases: edges turning by
// at least 30 degrees).
//   clean_runner outliers SHAPE N SEED OUT            issue 28's outlier scan: N area-uniform
//                                                     samples, Gaussian noise along the normal of
//                                                     sigma 0.001 x diagonal, N/100 outliers
//                                                     uniform in the bounding box grown by 10 %;
//                                                     fields outlier (0/1), truth_distance, edge_distance, index
//   clean_runner outlier_score FILE SIGMA NEAR        what is left of such a scan: outliers
//                                                     beyond 5 sigma of the surface, surface samples
//                                                     (all, and within NEAR of a crease)
//   clean_runner spacing IN                           mean spacing of a file
//   clean_runner quality                              outlier precision/recall, RMS, edges
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../../tests/support/features_shapes.cpp"
#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/clean/remove_duplicates.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/clean/smooth_points.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "../bench_util.h"

using namespace pointsurf;

namespace {

using pointsurf::bench::Clock;
using pointsurf::bench::peak_rss_mb;
using pointsurf::bench::seconds_since;

// An axis-aligned box, possibly flat (a face) or thin (an edge); distance by clamping.
struct Box {
  Vector3d min, max;
  double distance(const Vector3d& p) const { return (p - p.cwiseMax(min).cwiseMin(max)).norm(); }
};

// A polyhedral shape with axis-aligned faces: faces with outward normals, and crease edges.
struct Shape {
  std::vector<Box> faces;
  std::vector<Vector3d> normals;
  std::vector<Box> edges;
  double surface_distance(const Vector3d& p) const {
    double d = INFINITY;
    for (const Box& f : faces) d = std::min(d, f.distance(p));
    return d;
  }
  double edge_distance(const Vector3d& p) const {
    double d = INFINITY;
    for (const Box& e : edges) d = std::min(d, e.distance(p));
    return d;
  }
};

// Adds the 6 faces and 12 edges of the box [lo, hi] (faces listed in `skip` are left out).
void add_box(Shape& s, const Vector3d& lo, const Vector3d& hi) {
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      Box f{lo, hi};
      f.min[axis] = f.max[axis] = side == 0 ? lo[axis] : hi[axis];
      Vector3d n = Vector3d::Zero();
      n[axis] = side == 0 ? -1.0 : 1.0;
      s.faces.push_back(f);
      s.normals.push_back(n);
    }
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        Box e{lo, hi};
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        e.min[u] = e.max[u] = a == 0 ? lo[u] : hi[u];
        e.min[v] = e.max[v] = b == 0 ? lo[v] : hi[v];
        s.edges.push_back(e);
      }
  }
}

Shape cube_shape() {
  Shape s;
  add_box(s, Vector3d(-1, -1, -1), Vector3d(1, 1, 1));
  return s;
}

// A CAD-like part: an L-shaped prism (cross-section in x-z, extruded along y), with five convex
// 90-degree creases, one concave one, and the cap outlines. Faces are listed piecewise.
Shape part_shape() {
  Shape s;
  auto face = [&](Vector3d lo, Vector3d hi, Vector3d n) {
    s.faces.push_back({lo, hi});
    s.normals.push_back(n);
  };
  auto edge = [&](Vector3d a, Vector3d b) { s.edges.push_back({a.cwiseMin(b), a.cwiseMax(b)}); };
  face({0, 0, 0}, {2, 1, 0}, {0, 0, -1});   // bottom
  face({2, 0, 0}, {2, 1, 1}, {1, 0, 0});    // right
  face({1, 0, 1}, {2, 1, 1}, {0, 0, 1});    // step top
  face({1, 0, 1}, {1, 1, 2}, {1, 0, 0});    // riser
  face({0, 0, 2}, {1, 1, 2}, {0, 0, 1});    // top
  face({0, 0, 0}, {0, 1, 2}, {-1, 0, 0});   // left
  for (double y : {0.0, 1.0}) {             // caps: the L as two rectangles
    const Vector3d n(0, y == 0.0 ? -1 : 1, 0);
    face({0, y, 0}, {2, y, 1}, n);
    face({0, y, 1}, {1, y, 2}, n);
  }
  const std::vector<Vector3d> outline = {{0, 0, 0}, {2, 0, 0}, {2, 0, 1}, {1, 0, 1}, {1, 0, 2}, {0, 0, 2}};
  for (std::size_t i = 0; i < outline.size(); ++i) {
    const Vector3d a = outline[i], b = outline[(i + 1) % outline.size()];
    edge(a, a + Vector3d(0, 1, 0));
    edge(a, b);
    edge(a + Vector3d(0, 1, 0), b + Vector3d(0, 1, 0));
  }
  return s;
}

PointCloud sample_shape(const Shape& s, std::size_t n, std::uint64_t seed) {
  std::vector<double> areas;
  for (const Box& f : s.faces) {
    const Vector3d e = f.max - f.min;
    areas.push_back(std::max(e.x() * e.y(), 0.0) + std::max(e.y() * e.z(), 0.0) + std::max(e.x() * e.z(), 0.0));
  }
  std::mt19937_64 rng(seed);
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t f = pick(rng);
    const Box& b = s.faces[f];
    cloud.positions.push_back(b.min + (b.max - b.min).cwiseProduct(Vector3d(u(rng), u(rng), u(rng))));
    cloud.normals.push_back(s.normals[f]);
  }
  return cloud;
}

PointCloud sample_sphere(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  PointCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    Vector3d p(g(rng), g(rng), g(rng));
    p.normalize();
    cloud.positions.push_back(p);
    cloud.normals.push_back(p);
  }
  return cloud;
}

void add_noise(PointCloud& cloud, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (Vector3d& p : cloud.positions) p += Vector3d(g(rng), g(rng), g(rng));
}

// A mesh file as the true surface: exact distances to its triangles, and to its sharp edges
// (turning by at least 30 degrees, as issue 13's feature truth).
struct MeshTruth {
  TriangleMesh mesh;
  std::unique_ptr<TriangleBvh> bvh;
  std::unique_ptr<test::SharpEdges> sharp;
};

struct Truth {
  std::string name;
  Shape shape;  // unused for the sphere and meshes
  std::shared_ptr<const MeshTruth> mesh;
  double surface(const Vector3d& p) const {
    if (mesh) return std::sqrt(mesh->bvh->closest(p).squared_distance);
    return name == "sphere" ? std::abs(p.norm() - 1.0) : shape.surface_distance(p);
  }
  double edge(const Vector3d& p) const {
    if (mesh) return mesh->sharp->distance(p);
    return name == "sphere" ? INFINITY : shape.edge_distance(p);
  }
};

Truth truth(const std::string& name) {
  if (name == "sphere") return {name, {}, {}};
  if (name == "cube") return {name, cube_shape(), {}};
  if (name == "part") return {name, part_shape(), {}};
  if (name.size() > 4 && name.find('.') != std::string::npos) {
    auto m = std::make_shared<MeshTruth>();
    m->mesh = read_mesh(name).mesh;
    m->bvh = std::make_unique<TriangleBvh>(m->mesh);
    m->sharp = std::make_unique<test::SharpEdges>(m->mesh, 30.0);
    return {name, {}, std::move(m)};
  }
  throw UsageError(fmt::format("unknown shape '{}': expected sphere, cube, part or a mesh file", name));
}

PointCloud sample(const Truth& t, std::size_t n, std::uint64_t seed) {
  if (t.mesh) return test::sample_mesh_features(t.mesh->mesh, n, 30.0, seed).cloud;
  return t.name == "sphere" ? sample_sphere(n, seed) : sample_shape(t.shape, n, seed);
}

// RMS distance to the true surface: all points, points within 2 spacings of a crease, and
// flat points farther than 5 spacings from every crease.
nlohmann::json score(const Truth& t, const std::vector<Vector3d>& points, double spacing) {
  double all = 0, edge = 0, flat = 0;
  std::size_t n_edge = 0, n_flat = 0;
  for (const Vector3d& p : points) {
    const double d2 = std::pow(t.surface(p), 2), e = t.edge(p);
    all += d2;
    if (e <= 2.0 * spacing) edge += d2, ++n_edge;
    if (e > 5.0 * spacing) flat += d2, ++n_flat;
  }
  nlohmann::json j = {{"rms_all", std::sqrt(all / double(points.size()))}, {"points", points.size()}};
  if (n_edge > 0) j["rms_edge"] = std::sqrt(edge / double(n_edge));
  if (n_flat > 0) j["rms_flat"] = std::sqrt(flat / double(n_flat));
  return j;
}

// Noisy shape with PCA normals (k 30) oriented outward (MST), as a scanner pipeline would give.
PointCloud synth(const Truth& t, std::size_t n, double noise_in_spacings, std::uint64_t seed, double& spacing) {
  PointCloud cloud = sample(t, n, seed);
  spacing = mean_spacing(cloud.positions);
  add_noise(cloud, noise_in_spacings * spacing, seed + 1);
  cloud.normals.clear();
  const KdTree tree(cloud.positions);
  estimate_normals(cloud, {.keep_variation = false}, &tree);
  orient_normals(cloud, {}, &tree);
  return cloud;
}

// Issue 28's outlier scan (see the top): surface samples then outliers, with their truth.
nlohmann::json outlier_scan(const Truth& t, std::size_t n, std::uint64_t seed, const std::string& out) {
  if (!t.mesh) throw UsageError("outliers: SHAPE must be a mesh file");
  test::FeatureShape shape = test::sample_mesh_features(t.mesh->mesh, n, 30.0, seed);
  PointCloud& cloud = shape.cloud;
  const BoundingBox box = bounding_box(t.mesh->mesh.vertices.positions);
  const double diagonal = box.diagonal(), sigma = 0.001 * diagonal;
  std::mt19937_64 rng(seed * 7919 + 1);
  std::normal_distribution<double> g(0.0, sigma);
  for (std::size_t i = 0; i < n; ++i) cloud.positions[i] += g(rng) * cloud.normals[i];
  const Vector3d grow = 0.05 * box.extent();
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::size_t outliers = n / 100;
  for (std::size_t i = 0; i < outliers; ++i) {
    const Vector3d r(u(rng), u(rng), u(rng));
    cloud.positions.push_back(box.min - grow + r.cwiseProduct(box.extent() + 2.0 * grow));
  }
  cloud.normals.clear();
  std::vector<double>& is_outlier = cloud.fields.add("outlier", cloud.size(), ScalarType::UInt8).values;
  std::vector<double>& truth = cloud.fields.add("truth_distance", cloud.size()).values;
  std::vector<double>& edge = cloud.fields.add("edge_distance", cloud.size()).values;
  std::vector<double>& index = cloud.fields.add("index", cloud.size(), ScalarType::UInt32).values;
  std::size_t far = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    is_outlier[i] = i >= n ? 1.0 : 0.0;
    index[i] = double(i);
    truth[i] = t.surface(cloud.positions[i]);
    edge[i] = i < n ? shape.edge_distance[i] : t.edge(cloud.positions[i]);
    if (i >= n && truth[i] > 5.0 * sigma) ++far;
  }
  write_point_cloud(out, cloud);
  return {{"stage", "outliers"}, {"shape", t.name}, {"points", cloud.size()}, {"surface", n}, {"outliers", outliers},
          {"far_outliers", far}, {"sigma", sigma}, {"diagonal", diagonal}, {"spacing", mean_spacing(cloud.positions)}};
}

// What a cleaning left of an outlier scan: outliers beyond 5 sigma, surface samples (and those
// within 2 spacings of a crease, given in cloud units).
nlohmann::json outlier_score(const PointCloud& cloud, double sigma, double near_edge) {
  const ScalarField* is_outlier = cloud.fields.find("outlier");
  const ScalarField* truth = cloud.fields.find("truth_distance");
  const ScalarField* edge = cloud.fields.find("edge_distance");
  if (!is_outlier || !truth || !edge) throw UsageError("outlier_score: the file lacks the outlier scan's fields");
  std::size_t far = 0, outliers = 0, surface = 0, surface_near_edge = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (is_outlier->values[i] != 0.0) {
      ++outliers;
      if (truth->values[i] > 5.0 * sigma) ++far;
    } else {
      ++surface;
      if (edge->values[i] <= near_edge) ++surface_near_edge;
    }
  }
  return {{"stage", "outlier_score"}, {"far_outliers_left", far}, {"outliers_left", outliers}, {"surface_left", surface},
          {"surface_near_edge_left", surface_near_edge}};
}

void write_indices(const std::string& path, const std::vector<std::uint32_t>& kept) {
  std::ofstream out(path);
  for (std::uint32_t i : kept) out << i << '\n';
}

// Appends `count` drift points (pushed along the true normal by 3..15 spacings) and `count`
// scattered points in the bounding box (>= 5 spacings from the surface). Returns their indices.
std::vector<std::uint32_t> inject_outliers(PointCloud& cloud, const std::vector<Vector3d>& true_normals, const Truth& t,
                                           std::size_t count, double spacing, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, cloud.size() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const BoundingBox box = bounding_box(cloud.positions);
  std::vector<std::uint32_t> indices;
  std::vector<Vector3d> extra;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = pick(rng);
    extra.push_back(cloud.positions[j] + (3.0 + 12.0 * u(rng)) * spacing * true_normals[j]);
  }
  while (extra.size() < 2 * count) {
    const Vector3d p = box.min + box.extent().cwiseProduct(Vector3d(u(rng), u(rng), u(rng)));
    if (t.surface(p) >= 5.0 * spacing) extra.push_back(p);
  }
  for (const Vector3d& p : extra) {
    indices.push_back(static_cast<std::uint32_t>(cloud.size()));
    cloud.positions.push_back(p);
  }
  return indices;
}

nlohmann::json detection(const OutlierResult& r, std::size_t n, const std::vector<std::uint32_t>& outliers) {
  std::vector<bool> kept(n, false), truth(n, false);
  for (std::uint32_t i : r.kept) kept[i] = true;
  for (std::uint32_t i : outliers) truth[i] = true;
  std::size_t removed = 0, hit = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!kept[i]) ++removed, hit += truth[i];
  return {{"removed", removed},
          {"precision", removed == 0 ? 1.0 : double(hit) / double(removed)},
          {"recall", double(hit) / double(outliers.size())}};
}

void quality() {
  for (const std::string name : {"sphere", "cube", "part"}) {
    const Truth t = truth(name);
    const std::size_t n = 100000;
    // Outliers: 0.5 spacing noise, 1% outliers.
    PointCloud clean = sample(t, n, 21);
    const std::vector<Vector3d> true_normals = clean.normals;
    const double spacing = mean_spacing(clean.positions);
    add_noise(clean, 0.5 * spacing, 22);
    clean.normals.clear();
    const std::vector<std::uint32_t> outliers = inject_outliers(clean, true_normals, t, n / 200, spacing, 23);
    nlohmann::json row = {{"shape", name}, {"points", clean.size()}, {"outliers", outliers.size()}, {"noise_in_spacings", 0.5}};
    row["sor"] = detection(remove_statistical_outliers(clean), clean.size(), outliers);
    row["radius"] = detection(remove_radius_outliers(clean), clean.size(), outliers);
    row["ransac"] = detection(remove_ransac_outliers(clean), clean.size(), outliers);
    fmt::print("{}\n", nlohmann::json{{"stage", "outlier_quality"}, {"result", row}}.dump());

    // Denoising: RMS to the true surface before and after, near creases and on flat parts.
    double s = 0.0;
    const PointCloud noisy = synth(t, n, 0.5, 31, s);
    nlohmann::json smooth = {{"shape", name}, {"points", n}, {"noise_in_spacings", 0.5}, {"spacing", s}};
    smooth["before"] = score(t, noisy.positions, s);
    PointCloud b = noisy, tri = noisy;
    auto start = Clock::now();
    smooth_bilateral(b);
    smooth["bilateral"] = score(t, b.positions, s);
    smooth["bilateral"]["seconds"] = seconds_since(start);
    start = Clock::now();
    smooth_trilateral(tri);
    smooth["trilateral"] = score(t, tri.positions, s);
    smooth["trilateral"]["seconds"] = seconds_since(start);
    fmt::print("{}\n", nlohmann::json{{"stage", "smooth_quality"}, {"result", smooth}}.dump());
  }
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::vector<std::string> a(argv + 1, argv + argc);
    if (a.size() == 5 && (a[0] == "sor" || a[0] == "radius")) {
      const PointCloud cloud = read_point_cloud(a[1]).cloud;
      const auto start = Clock::now();
      const KdTree tree(cloud.positions);
      const double tree_seconds = seconds_since(start);
      const OutlierResult r = a[0] == "sor"
                                  ? remove_statistical_outliers(cloud, {.k = std::stoi(a[2]), .std_ratio = std::stod(a[3])}, &tree)
                                  : remove_radius_outliers(cloud, {.min_neighbours = std::stoi(a[2]), .radius = Length::cloud(std::stod(a[3]))}, &tree);
      const double total = seconds_since(start);
      write_indices(a[4], r.kept);
      fmt::print("{}\n", nlohmann::json{{"tool", "pointsurf"}, {"stage", a[0]}, {"points", cloud.size()}, {"seconds", total},
                                        {"tree_seconds", tree_seconds}, {"kept", r.kept.size()}, {"threshold", r.threshold},
                                        {"peak_rss_mb", peak_rss_mb()}}
                             .dump());
    } else if (a.size() == 4 && a[0] == "smooth") {
      PointCloud cloud = read_point_cloud(a[2]).cloud;
      const auto start = Clock::now();
      const KdTree tree(cloud.positions);
      const SmoothResult r = a[1] == "bilateral" ? smooth_bilateral(cloud, {}, &tree) : smooth_trilateral(cloud, {}, &tree);
      const double total = seconds_since(start);
      write_point_cloud(a[3], cloud);
      fmt::print("{}\n", nlohmann::json{{"tool", "pointsurf"}, {"stage", a[1]}, {"points", cloud.size()}, {"seconds", total},
                                        {"rms_displacement", r.rms_displacement}, {"peak_rss_mb", peak_rss_mb()}}
                             .dump());
    } else if ((a.size() == 5 || a.size() == 6) && a[0] == "synth") {
      double spacing = 0.0;
      const PointCloud cloud = synth(truth(a[1]), std::stoul(a[2]), std::stod(a[3]), a.size() == 6 ? std::stoul(a[5]) : 1, spacing);
      write_point_cloud(a[4], cloud);
      fmt::print("{}\n", nlohmann::json{{"stage", "synth"}, {"shape", a[1]}, {"points", cloud.size()}, {"spacing", spacing}}.dump());
    } else if (a.size() == 3 && a[0] == "score") {
      const PointCloud cloud = read_point_cloud(a[2]).cloud;
      // Spacing of a clean sampling of the shape with as many points (the same for every tool).
      const Truth t = truth(a[1]);
      nlohmann::json j = score(t, cloud.positions, mean_spacing(sample(t, cloud.size(), 1).positions));
      j["stage"] = "score";
      j["file"] = a[2];
      fmt::print("{}\n", j.dump());
    } else if (a.size() == 5 && a[0] == "outliers") {
      fmt::print("{}\n", outlier_scan(truth(a[1]), std::stoul(a[2]), std::stoul(a[3]), a[4]).dump());
    } else if (a.size() == 4 && a[0] == "outlier_score") {
      fmt::print("{}\n", outlier_score(read_point_cloud(a[1]).cloud, std::stod(a[2]), std::stod(a[3])).dump());
    } else if (a.size() == 2 && a[0] == "spacing") {
      const PointCloud cloud = read_point_cloud(a[1]).cloud;
      fmt::print("{}\n", nlohmann::json{{"stage", "spacing"}, {"points", cloud.size()}, {"spacing", mean_spacing(cloud.positions)}}.dump());
    } else if (a.size() == 1 && a[0] == "quality") {
      quality();
    } else {
      fmt::print(stderr, "usage: see the comment at the top of bench/clean/clean_runner.cpp\n");
      return 1;
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "clean_runner: {}\n", e.what());
    return 1;
  }
  return 0;
}
