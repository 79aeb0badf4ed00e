// SPDX-License-Identifier: GPL-3.0-or-later
// Times render_scene on a generated torus: a mesh of about N triangles or N points on it.
//   render_runner mesh|points N [WIDTHxHEIGHT] [supersample] [repeats] [field]
// Prints one JSON line: median wall seconds of the render, of the PNG encoding, CPU seconds,
// and the process's peak resident memory (run one configuration per process).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "../bench_util.h"
#include "pointsurf/render/render_scene.h"

using namespace pointsurf;

namespace {

Vector3d torus(double u, double v) {
  const double R = 3.0, r = 1.0;
  return {(R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)};
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: render_runner mesh|points N [WxH] [supersample] [repeats] [field]\n");
    return 1;
  }
  const std::string kind = argv[1];
  const std::size_t n = std::stoul(argv[2]);
  RenderParams p;
  if (argc > 3) std::sscanf(argv[3], "%dx%d", &p.size.width, &p.size.height);
  if (argc > 4) p.supersample = std::stoi(argv[4]);
  const int repeats = argc > 5 ? std::stoi(argv[5]) : 3;
  const bool with_field = argc > 6;
  PointCloud cloud;
  std::vector<Triangle> triangles;
  const Vector3d offset(596648.0, 4137000.0, 100.0);  // georeferenced coordinates, as scans come
  if (kind == "mesh") {
    const int nu = int(std::sqrt(double(n) / 2.0 * 3.0)), nv = std::max(3, int(double(n) / 2.0 / nu));
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) cloud.positions.push_back(offset + torus(2 * M_PI * i / nu, 2 * M_PI * j / nv));
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = ((i + 1) % nu) * nv + (j + 1) % nv, d = i * nv + (j + 1) % nv;
        triangles.emplace_back(a, b, c);
        triangles.emplace_back(a, c, d);
      }
  } else {
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> U(0.0, 2 * M_PI);
    std::normal_distribution<double> noise(0.0, 0.002);
    for (std::size_t i = 0; i < n; ++i) cloud.positions.push_back(offset + torus(U(rng), U(rng)) + Vector3d(noise(rng), noise(rng), noise(rng)));
  }
  if (with_field) {
    auto& f = cloud.fields.add("deviation", cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) f.values[i] = 0.01 * std::sin(5.0 * cloud.positions[i].x());
    p.field = "deviation";
  }
  std::vector<double> render_s, png_s;
  const double cpu0 = bench::cpu_seconds();
  std::size_t png_bytes = 0;
  for (int k = 0; k < repeats; ++k) {
    auto t = bench::Clock::now();
    const RenderResult r = render_scene(cloud, triangles, p);
    render_s.push_back(bench::seconds_since(t));
    t = bench::Clock::now();
    png_bytes = encode_png(r.image).size();
    png_s.push_back(bench::seconds_since(t));
  }
  const double cpu = (bench::cpu_seconds() - cpu0) / repeats;
  std::sort(render_s.begin(), render_s.end());
  std::sort(png_s.begin(), png_s.end());
  std::printf("{\"kind\": \"%s\", \"points\": %zu, \"triangles\": %zu, \"size\": \"%dx%d\", \"supersample\": %d, \"field\": %s, "
              "\"render_s\": %.4f, \"png_s\": %.4f, \"cpu_s\": %.4f, \"png_bytes\": %zu, \"peak_rss_mb\": %.1f}\n",
              kind.c_str(), cloud.size(), triangles.size(), p.size.width, p.size.height, p.supersample, with_field ? "true" : "false",
              render_s[render_s.size() / 2], png_s[png_s.size() / 2], cpu, png_bytes, bench::peak_rss_mb());
  return 0;
}
