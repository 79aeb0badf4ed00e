// SPDX-License-Identifier: GPL-3.0-or-later
// The two-pass Crust (Amenta, Bern, Kamvysselis 1998): a second Delaunay triangulation of the
// samples and their Voronoi poles; its triangles of samples are the candidates of the manifold
// extraction shared with the cocone (reconstruct/detail/delaunay_surface.h).
#include "pointsurf/reconstruct/crust.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <vector>

#include <tbb/parallel_sort.h>

#include "core/detail/progress_reporter.h"
#include "reconstruct/detail/delaunay_surface.h"

namespace pointsurf {
namespace {

/// The distinct finite poles (p+ and p-) of the representative samples.
std::vector<Vector3d> finite_poles(const detail::DelaunaySetup& setup) {
  const detail::PoleSet& poles = setup.poles;
  std::vector<Vector3d> out;
  out.reserve(2 * setup.p.size());
  for (std::size_t i = 0; i < setup.p.size(); ++i) {
    if (setup.cells.representative[i] != int(i)) continue;
    if (poles.positive[i].allFinite()) out.push_back(poles.positive[i]);
    if (poles.negative[i].allFinite()) out.push_back(poles.negative[i]);
  }
  const auto less = [](const Vector3d& a, const Vector3d& b) {
    return a.x() < b.x() || (a.x() == b.x() && (a.y() < b.y() || (a.y() == b.y() && a.z() < b.z())));
  };
  tbb::parallel_sort(out.begin(), out.end(), less);
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// The facets of `cells` whose three vertices are samples (index < samples), as sorted triples,
/// each once, in cell order.
std::vector<std::array<int, 3>> sample_facets(const detail::DelaunayCells& cells, int samples) {
  std::vector<std::array<int, 3>> out;
  for (std::size_t c = 0; c < cells.size(); ++c) {
    const auto& v = cells.vertex[c];
    for (int i = 0; i < 4; ++i) {
      if (std::size_t(cells.neighbor[c][i]) < c) continue;  // visited from the lower-numbered cell
      std::array<int, 3> tri{v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]};
      bool ok = true;
      for (int& q : tri) {
        if (q == detail::kInfiniteVertex || q >= samples) {
          ok = false;
          break;
        }
        q = cells.representative[std::size_t(q)];
      }
      if (!ok) continue;
      std::sort(tri.begin(), tri.end());
      out.push_back(tri);
    }
  }
  return out;
}

}  // namespace

const FieldTable<CrustParams>& CrustParams::fields() {
  static const FieldTable<CrustParams> table = [] {
    FieldTable<CrustParams> t;
    detail::add_delaunay_fields(t);
    return t;
  }();
  return table;
}

ReconstructionResult reconstruct_crust(const PointCloud& cloud, const CrustParams& params, const ProgressCallback& progress,
                                       CrustStats* stats_out) {
  const auto t_start = std::chrono::steady_clock::now();
  params.validate();
  CrustStats stats;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, 1);
  detail::DelaunaySetup setup = detail::prepare_delaunay(cloud, "crust", stats, reporter);
  setup.cells.vertex = {};
  setup.cells.neighbor = {};
  setup.cells.center = {};
  setup.cells.infinite = {};

  // The second triangulation: samples first (so the samples keep their indices), then poles.
  std::vector<Vector3d> points = setup.p;
  const std::vector<Vector3d> poles = finite_poles(setup);
  stats.poles = poles.size();
  points.insert(points.end(), poles.begin(), poles.end());
  const auto t0 = std::chrono::steady_clock::now();
  const detail::DelaunayCells second = detail::delaunay_cells(points);
  stats.seconds_delaunay += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  stats.second_delaunay_vertices = points.size() - second.duplicates;
  stats.second_delaunay_cells = second.finite_cells;
  points = {};
  reporter.report(0.65);
  reporter.throw_if_cancelled();
  std::vector<std::array<int, 3>> candidates = sample_facets(second, int(setup.p.size()));

  ReconstructionResult result = detail::extract_delaunay_surface(cloud, setup, std::move(candidates), params, stats, reporter);
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  stats.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  result.stats = detail::common_stats(stats,
                                      {{"poles", stats.poles},
                                       {"second_delaunay_vertices", stats.second_delaunay_vertices},
                                       {"second_delaunay_cells", stats.second_delaunay_cells}});
  if (stats_out) *stats_out = stats;
  return result;
}

}  // namespace pointsurf
