// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/segment/run_segment_bench.sh; prints one JSON line, writes N int32
// labels (-1 unassigned).
//   segment_runner ransac IN.ply TYPES EPSILON CLUSTER_EPSILON NORMAL_DEG MIN_POINTS PROBABILITY OUT.labels [SEED]
//       TYPES: all (plane, sphere, cylinder, cone: the CGAL peer's four) or plane
//   segment_runner euclidean IN.ply RADIUS OUT.labels
//   segment_runner region IN.ply K MAX_ANGLE_DEG MAX_VARIATION MIN_POINTS OUT.labels
//       (the input's normals; no feature barriers, as PCL's RegionGrowing has none)
#include <chrono>
#include <ctime>
#include <fstream>
#include <iostream>
#include <string>

#include <fmt/format.h>

#include "pointsurf/io/io.h"
#include "pointsurf/segment/segment.h"
#include "pointsurf/shape/primitives.h"

using namespace pointsurf;

namespace {

void write_labels(const std::string& path, const std::vector<std::int32_t>& labels) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), std::streamsize(labels.size() * 4));
}

double since(std::chrono::steady_clock::time_point t0) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (!((mode == "ransac" && (argc == 10 || argc == 11)) || (mode == "euclidean" && argc == 5) || (mode == "region" && argc == 8))) {
    std::cerr << "usage: see the header of bench/segment/segment_runner.cpp\n";
    return 1;
  }
  const PointCloud cloud = read_point_cloud(argv[2]).cloud;
  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();  // CPU of all threads: knn_all is parallel, PCL is not
  if (mode == "ransac") {
    PrimitiveParams p;
    if (std::string(argv[3]) == "plane") p.types = {PrimitiveType::Plane};
    p.epsilon = Length::cloud(std::stod(argv[4]));
    p.cluster_epsilon = Length::cloud(std::stod(argv[5]));
    p.max_normal_angle_deg = std::stod(argv[6]);
    p.min_points = std::stoul(argv[7]);
    p.probability = std::stod(argv[8]);
    if (argc == 11) p.seed = std::stoull(argv[10]);
    const PrimitiveResult r = detect_primitives(cloud, p);
    const double s = since(t0);
    std::string types;
    for (const Primitive& x : r.primitives) types += (types.empty() ? "" : ",") + std::string(primitive_type_name(x.type));
    write_labels(argv[9], r.labels);
    fmt::print("{{\"tool\": \"pointsurf\", \"seconds\": {:.4f}, \"primitives\": {}, \"types\": \"{}\", \"unassigned\": {}}}\n", s, r.primitives.size(),
               types, r.unassigned);
  } else {
    SegmentResult r;
    if (mode == "euclidean") {
      EuclideanParams p;
      p.radius = Length::cloud(std::stod(argv[3]));
      p.min_points = 1;
      r = segment_euclidean(cloud, p);
    } else {
      RegionGrowingParams p;
      p.k = std::stoi(argv[3]);
      p.max_angle_deg = std::stod(argv[4]);
      p.max_variation = std::stod(argv[5]);
      p.min_points = std::stoul(argv[6]);
      p.use_features = false;
      r = segment_region_growing(cloud, p);
    }
    const double s = since(t0);
    const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC;
    write_labels(argv[argc - 1], r.labels);
    fmt::print("{{\"tool\": \"pointsurf\", \"seconds\": {:.4f}, \"cpu_seconds\": {:.4f}, \"segments\": {}, \"unassigned\": {}}}\n", s, cpu, r.sizes.size(),
               r.unassigned);
  }
  return 0;
}
