// SPDX-License-Identifier: GPL-3.0-or-later
// CGAL peer for bench/segment: Shape_detection's efficient RANSAC (planes, spheres, cylinders,
// cones) on a raw dump (uint64 N, N x (x y z nx ny nz) float64).
//   cgal_efficient_ransac IN.bin EPSILON CLUSTER_EPSILON NORMAL_DEG MIN_POINTS PROBABILITY TYPES OUT.labels
// TYPES: "all" or "plane". Prints one JSON line; writes N int32 labels (-1 unassigned).
#include <algorithm>
#include <chrono>
#include <array>
#include <map>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using PointWithNormal = std::pair<Point, Vector>;
using Pwn = std::vector<PointWithNormal>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, Pwn, CGAL::First_of_pair_property_map<PointWithNormal>,
                                                              CGAL::Second_of_pair_property_map<PointWithNormal>>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;

int main(int argc, char** argv) {
  if (argc != 9) {
    std::cerr << "usage: cgal_efficient_ransac IN.bin EPSILON CLUSTER_EPSILON NORMAL_DEG MIN_POINTS PROBABILITY TYPES OUT.labels\n";
    return 1;
  }
  std::ifstream in(argv[1], std::ios::binary);
  std::uint64_t n = 0;
  in.read(reinterpret_cast<char*>(&n), 8);
  std::vector<double> raw(n * 6);
  in.read(reinterpret_cast<char*>(raw.data()), std::streamsize(raw.size() * 8));
  Pwn points(n);
  for (std::size_t i = 0; i < n; ++i)
    points[i] = {Point(raw[6 * i], raw[6 * i + 1], raw[6 * i + 2]), Vector(raw[6 * i + 3], raw[6 * i + 4], raw[6 * i + 5])};
  // Efficient_RANSAC sorts the input range in place (its octrees): labels are mapped back to the
  // input order by coordinates.
  std::map<std::array<double, 3>, std::size_t> original;
  for (std::size_t i = 0; i < n; ++i) original.emplace(std::array<double, 3>{raw[6 * i], raw[6 * i + 1], raw[6 * i + 2]}, i);
  const auto t0 = std::chrono::steady_clock::now();
  Ransac ransac;
  ransac.set_input(points);
  ransac.add_shape_factory<CGAL::Shape_detection::Plane<Traits>>();
  if (std::string(argv[7]) == "all") {
    ransac.add_shape_factory<CGAL::Shape_detection::Sphere<Traits>>();
    ransac.add_shape_factory<CGAL::Shape_detection::Cylinder<Traits>>();
    ransac.add_shape_factory<CGAL::Shape_detection::Cone<Traits>>();
  }
  Ransac::Parameters p;
  p.epsilon = std::stod(argv[2]);
  p.cluster_epsilon = std::stod(argv[3]);
  p.normal_threshold = std::cos(std::stod(argv[4]) * M_PI / 180.0);
  p.min_points = std::stoul(argv[5]);
  p.probability = std::stod(argv[6]);
  ransac.detect(p);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<std::int32_t> labels(n, -1);
  int index = 0;
  std::string types;
  for (const auto& shape : ransac.shapes()) {
    for (std::size_t i : shape->indices_of_assigned_points()) {
      const Point& q = points[i].first;
      labels[original.at({q.x(), q.y(), q.z()})] = index;
    }
    types += (types.empty() ? "" : ",") + std::string(dynamic_cast<CGAL::Shape_detection::Plane<Traits>*>(shape.get()) ? "plane"
                                                     : dynamic_cast<CGAL::Shape_detection::Sphere<Traits>*>(shape.get()) ? "sphere"
                                                     : dynamic_cast<CGAL::Shape_detection::Cylinder<Traits>*>(shape.get()) ? "cylinder"
                                                                                                                            : "cone");
    ++index;
  }
  std::ofstream(argv[8], std::ios::binary).write(reinterpret_cast<const char*>(labels.data()), std::streamsize(n * 4));
  std::printf("{\"tool\": \"cgal\", \"seconds\": %.4f, \"primitives\": %d, \"types\": \"%s\", \"unassigned\": %zu}\n", seconds, index, types.c_str(),
              std::size_t(std::count(labels.begin(), labels.end(), -1)));
  return 0;
}
