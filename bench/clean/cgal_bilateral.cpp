// SPDX-License-Identifier: GPL-3.0-or-later
// CGAL side of bench/clean/run_clean_bench.sh: bilateral_smooth_point_set (Huang et al. 2013)
// on a PLY with normals, timed (reading excluded), written back as PLY.
//   cgal_bilateral IN.ply OUT.ply K SHARPNESS_DEG ITERATIONS
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/read_points.h>
#include <CGAL/IO/write_points.h>
#include <CGAL/bilateral_smooth_point_set.h>
#include <CGAL/property_map.h>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using PointNormal = std::pair<Point, Vector>;

int main(int argc, char** argv) {
  if (argc != 6) {
    std::fprintf(stderr, "usage: cgal_bilateral IN.ply OUT.ply K SHARPNESS_DEG ITERATIONS\n");
    return 1;
  }
  std::vector<PointNormal> points;
  if (!CGAL::IO::read_points(argv[1], std::back_inserter(points),
                             CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointNormal>())
                                 .normal_map(CGAL::Second_of_pair_property_map<PointNormal>()))) {
    std::fprintf(stderr, "cgal_bilateral: cannot read %s\n", argv[1]);
    return 1;
  }
  const unsigned k = unsigned(std::atoi(argv[3]));
  const double sharpness = std::atof(argv[4]);
  const int iterations = std::atoi(argv[5]);
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < iterations; ++i)
    CGAL::bilateral_smooth_point_set<CGAL::Parallel_if_available_tag>(
        points, k,
        CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointNormal>())
            .normal_map(CGAL::Second_of_pair_property_map<PointNormal>())
            .sharpness_angle(sharpness));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  CGAL::IO::write_points(argv[2], points,
                         CGAL::parameters::point_map(CGAL::First_of_pair_property_map<PointNormal>())
                             .normal_map(CGAL::Second_of_pair_property_map<PointNormal>())
                             .stream_precision(17));
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  std::printf("{\"tool\": \"cgal\", \"stage\": \"bilateral\", \"points\": %zu, \"seconds\": %.6f, \"peak_rss_mb\": %.1f}\n", points.size(),
              seconds, double(usage.ru_maxrss) / 1024.0);
  return 0;
}
