// SPDX-License-Identifier: GPL-3.0-or-later
// Cocone reconstruction (Amenta, Choi, Dey, Leekha 2000): the candidates are the Delaunay
// triangles whose dual Voronoi edge meets the cocones of their three vertices; the Delaunay
// triangulation, the poles and the manifold extraction are shared with the Crust
// (reconstruct/detail/delaunay_surface.h).
#include "pointsurf/reconstruct/cocone.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "reconstruct/detail/delaunay_surface.h"

namespace pointsurf {
namespace {

/// Where a Voronoi edge end lies relative to the double cone of half-angle 90 - theta around the
/// pole vector at p: +1 inside the upper cone, -1 inside the lower cone, 0 in the cocone.
int cone_side(const Vector3d& direction, const Vector3d& pole, double sin_theta) {
  const double len = direction.norm();
  if (!(len > 0.0) || !std::isfinite(len)) return 0;
  const double c = direction.dot(pole) / len;
  if (c > sin_theta) return 1;
  if (c < -sin_theta) return -1;
  return 0;
}

/// The cocone test per Delaunay facet (visited from its lower-numbered cell): the facets whose
/// dual Voronoi edge (a segment between two circumcenters, or a ray for hull facets) meets the
/// cocone of each of their vertices, as sorted vertex triples in cell order.
std::vector<std::array<int, 3>> cocone_candidates(const detail::DelaunaySetup& setup, double cocone_angle_deg) {
  const detail::DelaunayCells& cells = setup.cells;
  const std::vector<Vector3d>& p = setup.p;
  const std::vector<Vector3d>& pole = setup.poles.axis;
  const std::size_t nc = cells.size();
  const double sin_theta = std::sin(cocone_angle_deg * std::numbers::pi / 180.0);
  std::vector<std::uint8_t> facet_flags(nc, 0);  // bit i: facet i passes
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nc), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      const auto& v = cells.vertex[c];
      std::uint8_t flags = 0;
      for (int i = 0; i < 4; ++i) {
        const std::size_t other = std::size_t(cells.neighbor[c][i]);
        if (other < c) continue;
        if (cells.infinite[c] && cells.infinite[other]) continue;
        const int a = v[(i + 1) % 4], b = v[(i + 2) % 4], d = v[(i + 3) % 4];
        if (a == detail::kInfiniteVertex || b == detail::kInfiniteVertex || d == detail::kInfiniteVertex) continue;
        bool keep = true;
        for (int q : {a, b, d}) {
          int side[2];
          const std::size_t ends[2] = {c, other};
          for (int e = 0; e < 2; ++e) {
            const std::size_t cell = ends[e];
            // a finite end is a circumcenter; an infinite end is the far end of a ray along the
            // hull normal, seen from p in that direction.
            const Vector3d dir = cells.infinite[cell] ? cells.center[cell] : Vector3d(cells.center[cell] - p[q]);
            side[e] = cone_side(dir, pole[q], sin_theta);
          }
          if (side[0] != 0 && side[1] != 0 && side[0] == side[1]) {
            keep = false;
            break;
          }
        }
        if (keep) flags |= std::uint8_t(1u << i);
      }
      facet_flags[c] = flags;
    }
  });
  std::vector<std::array<int, 3>> candidates;
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint8_t f = facet_flags[c];
    for (int i = 0; i < 4; ++i)
      if (f & (1u << i)) {
        const auto& v = cells.vertex[c];
        std::array<int, 3> tri{v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]};
        std::sort(tri.begin(), tri.end());
        candidates.push_back(tri);
      }
  }
  return candidates;
}

}  // namespace

const FieldTable<CoconeParams>& CoconeParams::fields() {
  static const FieldTable<CoconeParams> table = [] {
    FieldTable<CoconeParams> t;
    t.number("cocone_angle_deg", &CoconeParams::cocone_angle_deg, "Cocone half-angle theta").unit("degrees").range(0, 90, true, true);
    detail::add_delaunay_fields(t);
    return t;
  }();
  return table;
}

void CoconeParams::validate() const {
  if (!(cocone_angle_deg > 0.0 && cocone_angle_deg < 90.0))
    throw UsageError(fmt::format("cocone: cocone_angle_deg = {}, expected a value in (0, 90)", cocone_angle_deg));
  DelaunaySurfaceParams::validate("cocone");
  fields().validate(*this, "cocone");
}

ReconstructionResult reconstruct_cocone(const PointCloud& cloud, const CoconeParams& params,
                                        const ProgressCallback& progress, CoconeStats* stats_out) {
  const auto t_start = std::chrono::steady_clock::now();
  params.validate();
  CoconeStats stats;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, 1);
  detail::DelaunaySetup setup = detail::prepare_delaunay(cloud, "cocone", stats, reporter);
  std::vector<std::array<int, 3>> candidates = cocone_candidates(setup, params.cocone_angle_deg);
  // The cells are no longer needed (the representatives are).
  setup.cells.vertex = {};
  setup.cells.neighbor = {};
  setup.cells.center = {};
  setup.cells.infinite = {};
  ReconstructionResult result = detail::extract_delaunay_surface(cloud, setup, std::move(candidates), params, stats, reporter);
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  stats.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  result.stats = detail::common_stats(stats);
  if (stats_out) *stats_out = stats;
  return result;
}

}  // namespace pointsurf
