// SPDX-License-Identifier: GPL-3.0-or-later
// Whole-pipeline runner for bench/register/icp_pipeline.py: voxel grid, normals, FPFH, RANSAC,
// ICP on one pair, each step timed (median of REPEATS), with Open3D's global-registration
// recipe's parameters from the voxel size v: grid cell v (centroids, as voxel_down_sample);
// normals from at most 30 neighbours within 2 v; FPFH within 5 v, at most 100 neighbours; mutual
// matches, RANSAC inliers within 1.5 v, edge-length ratio 0.9, 100000 trials at most, confidence
// 0.999; point-to-plane ICP on the full clouds (their own normals) within 0.4 v, 30 iterations.
//   icp_pipeline_runner SOURCE TARGET VOXEL SEED MAX_NORMAL_DEG REPEATS
//     MAX_NORMAL_DEG: ICP's normal-angle check (180: off)
// Prints one JSON line: per-step median wall seconds, total, the RANSAC and final matrices.
#include <algorithm>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "../bench_util.h"
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/register/align.h"
#include "pointsurf/register/features.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/simplify/simplify.h"
#include "pointsurf/spatial/kd_tree.h"

using namespace pointsurf;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

std::string row_major(const RigidTransform& t) {
  const Eigen::Matrix4d m = t.matrix();
  std::string s;
  for (int i = 0; i < 16; ++i) s += fmt::format("{}{:.17g}", i == 0 ? "" : ", ", m(i / 4, i % 4));
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 7) {
    std::fprintf(stderr, "usage: see the header of bench/register/icp_pipeline_runner.cpp\n");
    return 1;
  }
  const PointCloud source = read_point_cloud(argv[1]).cloud, target = read_point_cloud(argv[2]).cloud;
  const double voxel = std::stod(argv[3]);
  const std::uint64_t seed = std::stoull(argv[4]);
  const double normal_deg = std::stod(argv[5]);
  const int repeats = std::stoi(argv[6]);
  std::vector<double> t_voxel, t_normals, t_fpfh, t_ransac, t_icp, t_total;
  RegistrationResult global, fine;
  std::size_t down_source = 0, down_target = 0;
  for (int k = 0; k < repeats; ++k) {
    auto t0 = bench::Clock::now();
    const auto start = t0;
    GridParams gp;
    gp.target.cell = voxel;
    PointCloud sd = simplify_grid(source, gp).cloud, td = simplify_grid(target, gp).cloud;
    t_voxel.push_back(bench::seconds_since(t0));
    down_source = sd.size();
    down_target = td.size();

    t0 = bench::Clock::now();
    const KdTree sd_tree(sd.positions), td_tree(td.positions);
    NormalParams np;
    np.neighborhood = NeighborhoodKind::Hybrid;
    np.k = 30;
    np.radius = Length::cloud(2.0 * voxel);
    np.keep_variation = false;
    estimate_normals(sd, np, &sd_tree);
    estimate_normals(td, np, &td_tree);
    t_normals.push_back(bench::seconds_since(t0));

    t0 = bench::Clock::now();
    DescriptorParams dp;
    dp.radius = Length::cloud(5.0 * voxel);
    dp.max_neighbors = 100;
    const Descriptors fs = compute_descriptors(sd, sd_tree, dp), ft = compute_descriptors(td, td_tree, dp);
    t_fpfh.push_back(bench::seconds_since(t0));

    t0 = bench::Clock::now();
    AlignParams ap;
    ap.max_distance = Length::cloud(1.5 * voxel);
    ap.mutual = true;
    ap.edge_length_ratio = 0.9;
    ap.max_iterations = 100000;
    ap.confidence = 0.999;
    ap.seed = seed;
    global = align_global(sd, fs, td, ft, td_tree, ap);
    t_ransac.push_back(bench::seconds_since(t0));

    t0 = bench::Clock::now();
    const KdTree tree(target.positions);
    IcpParams ip;
    ip.metric = IcpMetric::PointToPlane;
    ip.max_distance = Length::cloud(0.4 * voxel);
    ip.max_iterations = 30;
    ip.max_normal_deg = normal_deg;
    fine = icp(source, target, tree, global.transform, ip);
    t_icp.push_back(bench::seconds_since(t0));
    t_total.push_back(bench::seconds_since(start));
  }
  fmt::print("{{\"tool\": \"pointsurf\", \"voxel\": {:.6f}, \"normals\": {:.6f}, \"fpfh\": {:.6f}, \"ransac\": {:.6f}, \"icp\": {:.6f}, "
             "\"total\": {:.6f}, \"down_source\": {}, \"down_target\": {}, \"ransac_iterations\": {}, \"icp_iterations\": {}, "
             "\"ransac_matrix\": [{}], \"matrix\": [{}]}}\n",
             median(t_voxel), median(t_normals), median(t_fpfh), median(t_ransac), median(t_icp), median(t_total), down_source, down_target,
             global.iterations, fine.iterations, row_major(global.transform), row_major(fine.transform));
  return 0;
}
