// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {

const EnumNames<GridMode>& grid_mode_names() {
  static const EnumNames<GridMode> names{{{GridMode::Centroid, "centroid"}, {GridMode::Nearest, "nearest"}}};
  return names;
}

const FieldTable<GridParams>& GridParams::fields() {
  static const FieldTable<GridParams> table = [] {
    using P = GridParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.choice("mode", &P::mode, grid_mode_names(), "centroid (average each cell) or nearest (keep the sample nearest to it)");
    return t;
  }();
  return table;
}

void GridParams::validate() const { fields().validate(*this, "simplify_grid"); }

SimplifyResult simplify_grid(const PointCloud& cloud, const GridParams& params, const ProgressCallback& progress) {
  detail::check_simplify_input("simplify_grid", cloud, params.target, true);
  params.validate();
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
  const detail::CellLabels cells = detail::label_cells(cloud.positions, grid);
  const std::size_t m = cells.size();
  reporter.report(0.6);
  reporter.throw_if_cancelled();

  // Per-cell sums in input order: sequential reads of the points and scatter into m cells that
  // stay in cache, instead of gathering each cell's members from all over the cloud.
  const std::vector<std::uint32_t>& cell_of = cells.cell_of;
  const auto members = [&](std::size_t s) { return double(cells.count[s]); };
  std::vector<Vector3d> centroid(m, Vector3d::Zero());  // offsets from the grid origin
  for (std::size_t i = 0; i < n; ++i) centroid[cell_of[i]] += cloud.positions[i] - grid.origin;
  for (std::size_t s = 0; s < m; ++s) centroid[s] /= members(s);

  // The representative sample of each cell: nearest to its centroid (both modes; ties to the
  // lowest index).
  std::vector<std::size_t>& source = result.source_index;
  source.assign(m, 0);
  {
    std::vector<double> best(m, std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t s = cell_of[i];
      const double d = (cloud.positions[i] - grid.origin - centroid[s]).squaredNorm();
      if (d < best[s]) best[s] = d, source[s] = i;
    }
  }
  PointCloud& out = result.cloud;
  if (params.mode == GridMode::Nearest) {
    out = cloud.select(source);
  } else {
    out.positions.resize(m);
    for (std::size_t s = 0; s < m; ++s) out.positions[s] = grid.origin + centroid[s];
    if (cloud.has_normals()) {
      out.normals.assign(m, Vector3d::Zero());
      for (std::size_t i = 0; i < n; ++i) out.normals[cell_of[i]] += cloud.normals[i];
      for (Vector3d& v : out.normals) {
        const double len = v.norm();
        v = len > 0.0 ? Vector3d(v / len) : Vector3d::Zero();
      }
    }
    if (cloud.has_colors()) {
      out.colors.assign(m, Vector3f::Zero());
      for (std::size_t i = 0; i < n; ++i) out.colors[cell_of[i]] += cloud.colors[i];
      for (std::size_t s = 0; s < m; ++s) out.colors[s] /= float(members(s));
    }
    for (const ScalarField& f : cloud.fields) {
      ScalarField& g = out.fields.add(f.name, m, f.type);
      if (!scalar_type_is_float(f.type)) {  // labels and classes are not averaged
        for (std::size_t s = 0; s < m; ++s) g.values[s] = f.values[source[s]];
        continue;
      }
      std::fill(g.values.begin(), g.values.end(), 0.0);
      for (std::size_t i = 0; i < n; ++i) g.values[cell_of[i]] += f.values[i];
      for (std::size_t s = 0; s < m; ++s) g.values[s] /= members(s);
    }
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
