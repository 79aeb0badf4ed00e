// SPDX-License-Identifier: GPL-3.0-or-later
// CGAL's hierarchy_simplify_point_set (Pauly et al. 2002) as a peer for the simplify benchmark.
//   cgal_hierarchy CLOUD.xyz SIZE VARIATION OUT.xyz
// Reads "x y z" lines, simplifies with clusters of at most SIZE points and surface variation at
// most VARIATION, writes the kept points, prints one JSON line (time of the call alone).
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/hierarchy_simplify_point_set.h>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr, "usage: cgal_hierarchy CLOUD.xyz SIZE VARIATION OUT.xyz\n");
    return 1;
  }
  std::vector<Point> points;
  std::ifstream in(argv[1]);
  double x, y, z;
  while (in >> x >> y >> z) points.emplace_back(x, y, z);
  const std::size_t n = points.size();
  const auto t0 = std::chrono::steady_clock::now();
  const auto end = CGAL::hierarchy_simplify_point_set(
      points, CGAL::parameters::size(unsigned(std::atoi(argv[2]))).maximum_variation(std::atof(argv[3])));
  points.erase(end, points.end());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream out(argv[4]);
  out.precision(17);
  for (const Point& p : points) out << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("{\"tool\": \"cgal\", \"stage\": \"hierarchy\", \"points\": %zu, \"output_points\": %zu, \"seconds\": %.6f, "
              "\"peak_rss_mb\": %.1f}\n",
              n, points.size(), seconds, double(usage.ru_maxrss) / 1024.0);
  return 0;
}
