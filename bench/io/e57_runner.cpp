// SPDX-License-Identifier: GPL-3.0-or-later
// E57 read and write speed on a seeded N-point cloud (colours, intensity), float64 and
// scaled-integer coordinates, against binary PLY and LAS of the same cloud in the same run
// (interleaved, median of `runs`). Prints CSV: format,points,bytes,write_s,read_s,read_mpts_s.
// Usage: e57_runner [points=1000000] [runs=5] [dir=/tmp]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "pointsurf/io/io.h"

using namespace pointsurf;

int main(int argc, char** argv) {
  const std::size_t n = argc > 1 ? std::stoul(argv[1]) : 1000000;
  const int runs = argc > 2 ? std::stoi(argv[2]) : 5;
  const std::filesystem::path dir = argc > 3 ? argv[3] : "/tmp";
  PointCloud cloud;
  std::mt19937_64 rng(57);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ScalarField& intensity = cloud.fields.add("intensity", 0, ScalarType::Float32);
  for (std::size_t i = 0; i < n; ++i) {
    // A terrestrial-scan-like extent: 100 m, millimetre detail.
    cloud.positions.emplace_back(100 * u(rng), 100 * u(rng), 20 * u(rng));
    cloud.colors.emplace_back(float(rng() % 256) / 255.f, float(rng() % 256) / 255.f, float(rng() % 256) / 255.f);
    intensity.values.push_back(float(u(rng)));
  }
  struct Case {
    std::string name, file;
    WriteOptions options;
  };
  std::vector<Case> cases(4);
  cases[0] = {"e57_float64", "bench.e57", {}};
  cases[1] = {"e57_scaled_1e-4", "bench_scaled.e57", {}};
  cases[1].options.e57_scale = 1e-4;
  cases[2] = {"ply_binary", "bench.ply", {}};
  cases[3] = {"las", "bench.las", {}};
  std::map<std::string, std::vector<double>> write_s, read_s;
  using clock = std::chrono::steady_clock;
  for (int r = 0; r < runs; ++r)
    for (const Case& c : cases) {
      const auto t0 = clock::now();
      write_point_cloud(dir / c.file, cloud, c.options);
      const auto t1 = clock::now();
      const CloudReadResult back = read_point_cloud(dir / c.file);
      const auto t2 = clock::now();
      if (back.cloud.size() != n) return 1;
      write_s[c.name].push_back(std::chrono::duration<double>(t1 - t0).count());
      read_s[c.name].push_back(std::chrono::duration<double>(t2 - t1).count());
    }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  fmt::print("format,points,bytes,write_s,read_s,read_mpts_s\n");
  for (const Case& c : cases) {
    const double rs = median(read_s[c.name]);
    fmt::print("{},{},{},{:.4f},{:.4f},{:.1f}\n", c.name, n, std::filesystem::file_size(dir / c.file), median(write_s[c.name]), rs, n / rs / 1e6);
    std::filesystem::remove(dir / c.file);
  }
  return 0;
}
