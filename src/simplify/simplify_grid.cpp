// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "normals/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {

SimplifyResult simplify_grid(const PointCloud& cloud, const GridParams& params, const ProgressCallback& progress) {
  detail::check_simplify_input("simplify_grid", cloud, params.target, true);
  const std::size_t n = cloud.size();
  const BoundingBox box = bounding_box(cloud.positions);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);

  double cell = params.target.cell;
  if (cell == 0.0) {
    const std::size_t wanted = detail::target_count(params.target, n);
    const double extent = std::max(box.extent().maxCoeff(), 1e-300);
    if (wanted >= n) {
      // Every point its own cell: any cell below the smallest gap would do; the caller gets the
      // input back (averaging single points changes nothing).
      cell = 0.0;
    } else {
      // Start from a coarse grid (64 cells across) and solve on log count vs log cell.
      const std::size_t wanted_cells = wanted;
      cell = detail::solve_length(extent / 64.0, wanted_cells, 0.01, 8, [&](double c) {
               return detail::count_cells(cloud.positions, {}, true, detail::make_grid("simplify_grid", box, c));
             }).first;
    }
  }
  reporter.report(0.3);
  reporter.throw_if_cancelled();

  SimplifyResult result;
  result.input_points = n;
  if (cell == 0.0) {
    result.cloud = cloud;
    result.source_index.resize(n);
    for (std::size_t i = 0; i < n; ++i) result.source_index[i] = i;
    reporter.report(1.0);
    reporter.throw_if_cancelled();
    return result;
  }
  const detail::Grid grid = detail::make_grid("simplify_grid", box, cell);
  result.length_used = cell;
  const detail::GridCells cells = detail::sort_into_cells(cloud.positions, {}, true, grid);
  const std::size_t m = cells.size();
  reporter.report(0.6);
  reporter.throw_if_cancelled();

  // The representative sample of each cell: nearest to its centroid (both modes).
  std::vector<std::size_t>& source = result.source_index;
  source.resize(m);
  PointCloud& out = result.cloud;
  const bool centroid = params.mode == GridMode::Centroid;
  if (centroid) out.positions.resize(m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      const std::span<const std::uint32_t> members(cells.order.data() + cells.starts[s], cells.starts[s + 1] - cells.starts[s]);
      source[s] = detail::nearest_to_centroid(cloud.positions, members);
      if (centroid) {
        Vector3d sum = Vector3d::Zero();
        for (std::uint32_t i : members) sum += cloud.positions[i] - grid.origin;
        out.positions[s] = grid.origin + sum / double(members.size());
      }
    }
  });
  if (!centroid) {
    out = cloud.select(source);
  } else {
    if (cloud.has_normals()) {
      out.normals.resize(m);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t s = r.begin(); s != r.end(); ++s) {
          Vector3d sum = Vector3d::Zero();
          for (std::size_t q = cells.starts[s]; q != cells.starts[s + 1]; ++q) sum += cloud.normals[cells.order[q]];
          const double len = sum.norm();
          out.normals[s] = len > 0.0 ? Vector3d(sum / len) : Vector3d::Zero();
        }
      });
    }
    if (cloud.has_colors()) {
      out.colors.resize(m);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t s = r.begin(); s != r.end(); ++s) {
          Vector3f sum = Vector3f::Zero();
          for (std::size_t q = cells.starts[s]; q != cells.starts[s + 1]; ++q) sum += cloud.colors[cells.order[q]];
          out.colors[s] = sum / float(cells.starts[s + 1] - cells.starts[s]);
        }
      });
    }
    for (const ScalarField& f : cloud.fields) {
      ScalarField& g = out.fields.add(f.name, m, f.type);
      const bool average = scalar_type_is_float(f.type);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t s = r.begin(); s != r.end(); ++s) {
          if (!average) {  // labels and classes are not averaged
            g.values[s] = f.values[source[s]];
            continue;
          }
          double sum = 0.0;
          for (std::size_t q = cells.starts[s]; q != cells.starts[s + 1]; ++q) sum += f.values[cells.order[q]];
          g.values[s] = sum / double(cells.starts[s + 1] - cells.starts[s]);
        }
      });
    }
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
