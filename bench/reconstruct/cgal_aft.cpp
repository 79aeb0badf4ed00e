// SPDX-License-Identifier: GPL-3.0-or-later
// Peer for bench/reconstruct/run_cocone_bench.sh: CGAL 5.5's advancing front surface
// reconstruction (Cohen-Steiner and Da 2004) with its default parameters, on an ASCII XYZ file
// (x y z per line). Writes the mesh as OFF and prints one JSON line: seconds (reconstruction
// only, reading excluded), peak_rss_mb (getrusage, reading included), points, triangles.
// Built by the script: g++ -O2 -std=c++17 -I/usr/include/eigen3 cgal_aft.cpp -lgmp -lmpfr
#include <sys/resource.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <vector>

#include <CGAL/Advancing_front_surface_reconstruction.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = K::Point_3;

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: cgal_aft CLOUD.xyz OUT.off\n";
    return 1;
  }
  std::ifstream in(argv[1]);
  std::vector<Point> points;
  double x, y, z;
  while (in >> x >> y >> z) points.emplace_back(x, y, z);
  if (points.size() < 4) {
    std::cerr << "cgal_aft: fewer than 4 points in " << argv[1] << "\n";
    return 2;
  }
  std::vector<std::array<std::size_t, 3>> facets;
  const auto start = std::chrono::steady_clock::now();
  CGAL::advancing_front_surface_reconstruction(points.begin(), points.end(), std::back_inserter(facets));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::ofstream out(argv[2]);
  out.precision(17);
  out << "OFF\n" << points.size() << " " << facets.size() << " 0\n";
  for (const Point& p : points) out << p.x() << " " << p.y() << " " << p.z() << "\n";
  for (const auto& f : facets) out << "3 " << f[0] << " " << f[1] << " " << f[2] << "\n";
  std::printf("{\"tool\": \"cgal_aft\", \"points\": %zu, \"seconds\": %.6f, \"peak_rss_mb\": %.1f, \"triangles\": %zu}\n",
              points.size(), seconds, double(usage.ru_maxrss) / 1024.0, facets.size());
  return 0;
}
