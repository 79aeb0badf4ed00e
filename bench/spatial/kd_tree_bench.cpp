// SPDX-License-Identifier: GPL-3.0-or-later
// Micro-benchmarks of the kd-tree: build, and batch kNN in the tree's spatial order vs input order.
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "pointsurf/spatial/kd_tree.h"

namespace {

std::vector<Eigen::Vector3d> random_sphere(std::size_t n) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g;
  std::vector<Eigen::Vector3d> pts(n);
  for (auto& p : pts) {
    const double x = g(rng), y = g(rng), z = g(rng);
    p = Eigen::Vector3d(x, y, z).normalized();
  }
  return pts;
}

void build(benchmark::State& state) {
  const auto pts = random_sphere(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    pointsurf::KdTree tree(pts);
    benchmark::DoNotOptimize(tree.size());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(build)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void knn_all_spatial_order(benchmark::State& state) {
  const auto pts = random_sphere(static_cast<std::size_t>(state.range(0)));
  const pointsurf::KdTree tree(pts);
  for (auto _ : state) benchmark::DoNotOptimize(tree.knn_all({}, 30).neighbors.data());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(knn_all_spatial_order)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void knn_all_input_order(benchmark::State& state) {
  const auto pts = random_sphere(static_cast<std::size_t>(state.range(0)));
  const pointsurf::KdTree tree(pts);
  for (auto _ : state) benchmark::DoNotOptimize(tree.knn_all(pts, 30).neighbors.data());
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(knn_all_input_order)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

}  // namespace
