// SPDX-License-Identifier: GPL-3.0-or-later
// Peer for bench/shape/run_shape_bench.sh: CGAL::Monge_via_jet_fitting (Cazals and Pouget) on
// the k nearest neighbours of every point (CGAL's own kd-tree), sequential as CGAL ships it.
//   cgal_jet_curvature IN.bin K DEGREE OUT.bin
// IN.bin: uint64 N, then N × (x y z nx ny nz) float64 (written by shape_runner dump).
// OUT.bin: N × (k1 k2) float64 in the pointsurf sign convention (positive where the surface
// bends away from the given normal). Prints one JSON line with the times.
#include <sys/resource.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <vector>

#include <CGAL/Monge_via_jet_fitting.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Simple_cartesian.h>

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using Fitting = CGAL::Monge_via_jet_fitting<Kernel>;
using Traits = CGAL::Search_traits_3<Kernel>;
using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
using Tree = Search::Tree;

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

int main(int argc, char** argv) {
  if (argc != 5) {
    std::cerr << "usage: cgal_jet_curvature IN.bin K DEGREE OUT.bin\n";
    return 1;
  }
  const unsigned k = unsigned(std::stoul(argv[2]));
  const std::size_t degree = std::stoul(argv[3]);
  std::ifstream in(argv[1], std::ios::binary);
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  std::vector<double> raw(6 * n);
  in.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size() * sizeof(double)));
  if (!in) {
    std::cerr << "cannot read " << argv[1] << "\n";
    return 2;
  }
  std::vector<Point> points;
  std::vector<Vector> normals;
  points.reserve(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    points.emplace_back(raw[6 * i], raw[6 * i + 1], raw[6 * i + 2]);
    normals.emplace_back(raw[6 * i + 3], raw[6 * i + 4], raw[6 * i + 5]);
  }
  const auto t0 = std::chrono::steady_clock::now();
  Tree tree(points.begin(), points.end());
  tree.build();
  const auto t1 = std::chrono::steady_clock::now();
  const double c1 = cpu_seconds();
  std::vector<double> out(2 * n);
  std::vector<Point> neighbours;
  neighbours.reserve(k);
  for (std::uint64_t i = 0; i < n; ++i) {
    neighbours.clear();
    Search search(tree, points[i], k);
    for (const auto& hit : search) neighbours.push_back(hit.first);
    Fitting fitting;
    Fitting::Monge_form monge = fitting(neighbours.begin(), neighbours.end(), degree, 2);
    monge.comply_wrt_given_normal(normals[i]);
    // CGAL: positive where the surface bends towards the normal; pointsurf: away from it.
    out[2 * i] = -monge.principal_curvatures(1);
    out[2 * i + 1] = -monge.principal_curvatures(0);
  }
  const auto t2 = std::chrono::steady_clock::now();
  const double c2 = cpu_seconds();
  std::ofstream o(argv[4], std::ios::binary);
  o.write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size() * sizeof(double)));
  const auto seconds = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };
  std::printf("{\"tool\": \"cgal\", \"points\": %llu, \"k\": %u, \"degree\": %zu, \"tree_seconds\": %.6f, "
              "\"curvature_seconds\": %.6f, \"curvature_cpu_seconds\": %.6f, \"threads\": 1}\n",
              static_cast<unsigned long long>(n), k, degree, seconds(t0, t1), seconds(t1, t2), c2 - c1);
  return 0;
}
