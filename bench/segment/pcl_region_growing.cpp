// SPDX-License-Identifier: GPL-3.0-or-later
// PCL peer for bench/segment/run_segment_bench.sh: pcl::RegionGrowing (PCL 1.13, Debian's
// libpcl-dev) with the input's normals and the parameters of pointsurf's segment_region_growing.
// pointsurf grows over the k + 1 nearest points (the point itself included) and computes each
// point's surface variation l0 / (l0 + l1 + l2) from them; PCL gets the same as
// setNumberOfNeighbours(k + 1) and NormalEstimation::setKSearch(k + 1), whose `curvature` is that
// variation (its normals are replaced by the input's). The timer covers what pointsurf's covers:
// the kd-tree, the neighbourhoods, the variation and the growth (PCL builds its tree twice:
// once for NormalEstimation, once inside RegionGrowing::extract; both are timed and reported).
// Reads the raw dump of scene_io.py (uint64 N, N x 6 float64: x y z nx ny nz); coordinates are
// taken relative to their mean before the float conversion (outside the timer). Prints one JSON
// line and writes N int32 labels (-1: in no cluster of at least MIN_POINTS).
//   pcl_region_growing IN.bin K MAX_ANGLE_DEG MAX_VARIATION MIN_POINTS OUT.labels
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <string>
#include <vector>

#include <pcl/features/normal_3d.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/region_growing.h>

namespace {

double since(std::chrono::steady_clock::time_point t0) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 7) {
    std::cerr << "usage: pcl_region_growing IN.bin K MAX_ANGLE_DEG MAX_VARIATION MIN_POINTS OUT.labels\n";
    return 1;
  }
  const int k = std::stoi(argv[2]);
  const double angle_deg = std::stod(argv[3]);
  const double max_variation = std::stod(argv[4]);
  const int min_points = std::stoi(argv[5]);
  std::ifstream in(argv[1], std::ios::binary);
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), 8);
  std::vector<double> raw(n * 6);
  in.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size() * sizeof(double)));
  if (!in) {
    std::cerr << "pcl_region_growing: " << argv[1] << ": expected " << n << " x 6 doubles, file ends\n";
    return 2;
  }
  double mean[3] = {0, 0, 0};
  for (std::uint64_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) mean[c] += raw[6 * i + c] / double(n);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(n);
  for (std::uint64_t i = 0; i < n; ++i)
    (*cloud)[i] = pcl::PointXYZ(float(raw[6 * i] - mean[0]), float(raw[6 * i + 1] - mean[1]), float(raw[6 * i + 2] - mean[2]));

  const auto t0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  pcl::search::Search<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setSearchMethod(tree);
  estimation.setInputCloud(cloud);
  estimation.setKSearch(k + 1);
  estimation.compute(*normals);  // for `curvature`: the surface variation
  for (std::uint64_t i = 0; i < n; ++i) {
    pcl::Normal& x = (*normals)[i];
    x.normal_x = float(raw[6 * i + 3]);
    x.normal_y = float(raw[6 * i + 4]);
    x.normal_z = float(raw[6 * i + 5]);
  }
  const double variation_seconds = since(t0);

  const auto t1 = std::chrono::steady_clock::now();
  pcl::RegionGrowing<pcl::PointXYZ, pcl::Normal> rg;
  rg.setMinClusterSize(min_points);
  rg.setMaxClusterSize(std::numeric_limits<int>::max());
  rg.setSearchMethod(tree);
  rg.setNumberOfNeighbours(k + 1);
  rg.setInputCloud(cloud);
  rg.setInputNormals(normals);
  rg.setSmoothModeFlag(true);  // angle to the current point's normal, as pointsurf
  rg.setSmoothnessThreshold(float(angle_deg * M_PI / 180.0));
  rg.setCurvatureTestFlag(true);
  rg.setCurvatureThreshold(float(max_variation));
  rg.setResidualTestFlag(false);
  std::vector<pcl::PointIndices> clusters;
  rg.extract(clusters);
  const double region_seconds = since(t1);
  const double seconds = since(t0);
  const double cpu_seconds = double(std::clock() - c0) / CLOCKS_PER_SEC;

  std::vector<std::int32_t> labels(n, -1);
  std::size_t assigned = 0;
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices) {
      labels[std::size_t(i)] = std::int32_t(c);
      ++assigned;
    }
  std::ofstream(argv[6], std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), std::streamsize(labels.size() * 4));
  std::printf("{\"tool\": \"pcl\", \"seconds\": %.4f, \"cpu_seconds\": %.4f, \"variation_seconds\": %.4f, \"region_seconds\": %.4f, \"segments\": %zu, \"unassigned\": %zu}\n",
              seconds, cpu_seconds, variation_seconds, region_seconds, clusters.size(), std::size_t(n) - assigned);
  return 0;
}
