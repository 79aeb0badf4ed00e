// SPDX-License-Identifier: GPL-3.0-or-later
// ICP runner for bench/register/icp_bench.py: times the target's kd-tree plus icp() (what
// Open3D's registration_icp does inside one call) REPEATS times and prints one JSON line with
// the median wall and CPU (all threads) times and the last result.
//   icp_runner SOURCE TARGET START.txt point|plane MAX_DISTANCE MAX_ITERATIONS MAX_NORMAL_DEG RELATIVE REPEATS
//     START.txt: 16 numbers, the 4x4 start matrix row-major (source onto target)
//     RELATIVE: relative_fitness = relative_rmse (0: run to the iteration cap)
#include <algorithm>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "../bench_util.h"
#include "pointsurf/io/io.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/spatial/kd_tree.h"

using namespace pointsurf;

int main(int argc, char** argv) {
  if (argc != 10) {
    std::cerr << "usage: see the header of bench/register/icp_runner.cpp\n";
    return 1;
  }
  const PointCloud source = read_point_cloud(argv[1]).cloud, target = read_point_cloud(argv[2]).cloud;
  Eigen::Matrix4d start;
  std::ifstream in(argv[3]);
  for (int i = 0; i < 16; ++i) in >> start(i / 4, i % 4);
  if (!in) {
    std::cerr << "icp_runner: " << argv[3] << ": expected 16 numbers\n";
    return 2;
  }
  IcpParams p;
  p.metric = std::string(argv[4]) == "point" ? IcpMetric::PointToPoint : IcpMetric::PointToPlane;
  if (const double d = std::stod(argv[5]); d > 0.0) p.max_distance = Length::cloud(d);  // 0: the default, in spacings
  p.max_iterations = std::stoul(argv[6]);
  p.max_normal_deg = std::stod(argv[7]);
  p.relative_fitness = p.relative_rmse = std::stod(argv[8]);
  const int repeats = std::stoi(argv[9]);
  std::vector<double> seconds, cpu;
  RegistrationResult r;
  for (int k = 0; k < repeats; ++k) {
    const auto t0 = bench::Clock::now();
    const double c0 = bench::cpu_seconds();
    const KdTree tree(target.positions);
    r = icp(source, target, tree, RigidTransform::from_matrix(start), p);
    seconds.push_back(bench::seconds_since(t0));
    cpu.push_back(bench::cpu_seconds() - c0);
  }
  std::sort(seconds.begin(), seconds.end());
  std::sort(cpu.begin(), cpu.end());
  const Eigen::Matrix4d m = r.transform.matrix();
  std::string matrix;
  for (int i = 0; i < 16; ++i) matrix += fmt::format("{}{:.17g}", i == 0 ? "" : ", ", m(i / 4, i % 4));
  fmt::print("{{\"tool\": \"pointsurf\", \"seconds\": {:.6f}, \"cpu_seconds\": {:.6f}, \"fitness\": {:.6f}, \"inlier_rmse\": {:.9g}, \"iterations\": {}, \"converged\": {}, "
             "\"matrix\": [{}]}}\n",
             seconds[seconds.size() / 2], cpu[cpu.size() / 2], r.fitness, r.inlier_rmse, r.iterations, r.converged ? "true" : "false", matrix);
  return 0;
}
