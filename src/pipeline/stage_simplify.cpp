// SPDX-License-Identifier: GPL-3.0-or-later
// The simplify stage: six methods, one target (ratio, count or cell).
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/simplify/simplify.h"

namespace pointsurf::detail {
namespace {

// The library's Params of each method from its arguments: the run and the check before any
// work build them the same way, and the check calls their validate().
GridParams grid_params(const StageArgs& a) { return read_params<GridParams>(a); }
RandomParams random_params(const StageArgs& a) { return read_params<RandomParams>(a); }
CurvatureSimplifyParams curvature_simplify_params(const StageArgs& a) { return read_params<CurvatureSimplifyParams>(a); }
RegionalParams regional_params(const StageArgs& a) { return read_params<RegionalParams>(a); }
CurvatureDistanceParams curvature_distance_params(const StageArgs& a) { return read_params<CurvatureDistanceParams>(a); }
LfsParams lfs_params(const StageArgs& a) { return read_params<LfsParams>(a); }

// A method's own parameters: its table less the target (ratio, count, cell), declared once
// for every method.
template <class Params>
std::vector<ParamSpec> method_params(const std::string& method) {
  std::vector<ParamSpec> out;
  for (ParamSpec& p : params_of(Params::fields(), {method}))
    if (SimplifyTarget::fields().find(p.name) == nullptr) out.push_back(std::move(p));
  return out;
}

// What simplify reports.
struct Simplified {
  std::size_t input = 0, output = 0, removed = 0, feature_points = 0, boundary_points = 0, added = 0;
  double reduction = 0.0, length_used = 0.0;
  // How far the simplified cloud is from the full one, both ways (nearest neighbours).
  double input_to_output_mean = 0.0, input_to_output_max = 0.0, output_to_input_mean = 0.0, output_to_input_max = 0.0;
  double chamfer = 0.0, hausdorff = 0.0, chamfer_in_spacings = 0.0;
};
using SimplifiedTable = ResultTable<Simplified>;
const SimplifiedTable& simplified_counts() {
  static const SimplifiedTable table = [] {
    using S = Simplified;
    SimplifiedTable t;
    t.count("input", &S::input, "Points read");
    t.count("output", &S::output, "Points left");
    t.count("removed", &S::removed, "Input points removed");
    t.count("feature_points", &S::feature_points, "Feature points kept");
    t.count("boundary_points", &S::boundary_points, "Boundary points kept");
    t.count("added", &S::added, "Points added (lfs)");
    return t;
  }();
  return table;
}
const SimplifiedTable& reduction_metrics() {
  static const SimplifiedTable table = [] {
    SimplifiedTable t;
    t.number("reduction", &Simplified::reduction, "Input points per output point");
    return t;
  }();
  return table;
}
const SimplifiedTable& length_metrics() {  // methods that derive a length
  static const SimplifiedTable table = [] {
    SimplifiedTable t;
    t.number("length_used", &Simplified::length_used, "Length the method used (cell, distance)").with_unit("cloud units");
    return t;
  }();
  return table;
}
const SimplifiedTable& distance_metrics() {
  static const SimplifiedTable table = [] {
    using S = Simplified;
    const std::string u = "cloud units";
    SimplifiedTable t;
    t.number("input_to_output_mean", &S::input_to_output_mean, "Mean distance, input to output").with_unit(u).lower_is_better();
    t.number("input_to_output_max", &S::input_to_output_max, "Largest distance, input to output").with_unit(u).lower_is_better();
    t.number("output_to_input_mean", &S::output_to_input_mean, "Mean distance, output to input").with_unit(u).lower_is_better();
    t.number("output_to_input_max", &S::output_to_input_max, "Largest distance, output to input").with_unit(u).lower_is_better();
    t.number("chamfer", &S::chamfer, "Chamfer distance: the mean of both means").with_unit(u).lower_is_better();
    t.number("hausdorff", &S::hausdorff, "Hausdorff distance: the larger of both maxima").with_unit(u).lower_is_better();
    return t;
  }();
  return table;
}
const SimplifiedTable& chamfer_in_spacings_metrics() {
  static const SimplifiedTable table = [] {
    SimplifiedTable t;
    t.number("chamfer_in_spacings", &Simplified::chamfer_in_spacings, "Chamfer distance in mean spacings of the input")
        .with_unit("spacings")
        .lower_is_better();
    return t;
  }();
  return table;
}
std::vector<ResultSpec> simplify_specs() {
  std::vector<ResultSpec> out = counted(simplified_counts().specs());
  for (const SimplifiedTable* t : {&reduction_metrics(), &length_metrics(), &distance_metrics(), &chamfer_in_spacings_metrics()}) append(out, t->specs());
  return out;
}

void run_simplify(StageRun& run) {
  const StageArgs& a = run.args;
  const std::string& method = a.method();
  DataItem& item = run.context.item(run.output);
  const PointCloud& cloud = item.cloud();
  const bool surface = method != "grid" && method != "random";
  if (surface && cloud.size() < 3) throw InputError(fmt::format("{}; method {} needs at least 3", plural(cloud.size(), "point"), method));
  const KdTree* tree = cloud.size() >= 2 ? &run.context.tree(run.output) : nullptr;
  const double spacing = cloud.size() >= 2 ? run.context.mean_spacing(run.output) : 0.0;
  const ProgressCallback progress = sub_progress(run.progress, 0.0, 0.9);
  SimplifyResult r;
  if (method == "grid") {
    r = simplify_grid(cloud, grid_params(a), progress);
  } else if (method == "random") {
    r = simplify_random(cloud, random_params(a));
  } else if (method == "curvature") {
    const CurvatureSimplifyParams p = curvature_simplify_params(a);
    r = simplify_curvature(cloud, p, tree, progress);
  } else if (method == "regional") {
    RegionalParams p = regional_params(a);
    p.spacing = spacing;
    r = simplify_regional(cloud, p, tree, progress);
  } else if (method == "curvature-distance") {
    const CurvatureDistanceParams p = curvature_distance_params(a);
    r = simplify_curvature_distance(cloud, p, tree, progress);
  } else {
    const LfsParams p = lfs_params(a);
    r = resample_lfs(cloud, p, tree, progress);
  }
  StageRecord& rec = run.record;
  const std::size_t input = cloud.size();
  const double reduction = r.reduction();
  const std::size_t kept_inputs = r.cloud.size() - r.added_points;
  Simplified report;
  report.input = input;
  report.output = r.cloud.size();
  report.removed = input - kept_inputs;
  report.feature_points = r.feature_points;
  report.boundary_points = r.boundary_points;
  report.added = r.added_points;
  report.reduction = reduction;
  report.length_used = r.length_used;
  rec.add_counts(simplified_counts(), report);
  rec.add(reduction_metrics(), report);
  if (r.length_used > 0.0) rec.add(length_metrics(), report);
  // How far the simplified cloud is from the full one, both ways.
  auto summarise = [](const NeighborLists& lists) {
    double sum = 0.0, worst = 0.0;
    for (const Neighbor& nb : lists.neighbors) {
      const double d = std::sqrt(nb.squared_distance);
      sum += d;
      worst = std::max(worst, d);
    }
    return std::pair{sum / double(std::max<std::size_t>(lists.neighbors.size(), 1)), worst};
  };
  std::pair<double, double> out_to_in{0.0, 0.0};
  if (tree != nullptr && !r.cloud.empty()) out_to_in = summarise(tree->knn_all(r.cloud.positions, 1));
  std::vector<Vector3d> input_positions = std::move(item.cloud().positions);
  if (!item.mesh.triangles.empty() || item.is_mesh) drop_faces(item, rec);
  item.cloud() = std::move(r.cloud);
  if (tree != nullptr && !item.cloud().empty()) {
    const auto in_to_out = summarise(run.context.tree(run.output).knn_all(input_positions, 1));
    report.input_to_output_mean = in_to_out.first;
    report.input_to_output_max = in_to_out.second;
    report.output_to_input_mean = out_to_in.first;
    report.output_to_input_max = out_to_in.second;
    report.chamfer = 0.5 * (in_to_out.first + out_to_in.first);
    report.hausdorff = std::max(in_to_out.second, out_to_in.second);
    report.chamfer_in_spacings = spacing > 0.0 ? 0.5 * (in_to_out.first + out_to_in.first) / spacing : 0.0;
    rec.add(distance_metrics(), report);
    if (spacing > 0.0) rec.add(chamfer_in_spacings_metrics(), report);
  }
  run.progress ? (void)run.progress(1.0) : (void)0;
  std::string extra;
  if (r.feature_points > 0) extra += fmt::format(", {} kept", plural(r.feature_points, "feature point"));
  if (r.added_points > 0) extra += fmt::format(", {} added", plural(r.added_points, "point"));
  rec.summary = fmt::format("simplify: {} -> {} ({}, {:.2f}x){}", plural(input, "point"), plural(item.cloud().size(), "point"), method,
                            reduction, extra);
}

}  // namespace

StageSpec simplify_stage() {
  StageSpec s;
  s.name = "simplify";
  s.summary = "Fewer points that keep the surface: grid, random, curvature, regional, curvature-distance or lfs";
  s.description = "The output size is one of ratio, count or cell (a length).";
  s.order = 40;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.methods = {"grid", "random", "curvature", "regional", "curvature-distance", "lfs"};
  s.default_method = "grid";
  const std::vector<std::string> with_cell = {"grid", "regional", "curvature-distance", "lfs"};
  s.params = params_of(SimplifyTarget::fields());
  for (ParamSpec& p : s.params)
    if (p.name == "cell") p.methods = with_cell;  // random and curvature take no cell
  append(s.params, method_params<GridParams>("grid"));
  append(s.params, method_params<RandomParams>("random"));
  append(s.params, method_params<CurvatureSimplifyParams>("curvature"));
  append(s.params, method_params<RegionalParams>("regional"));
  append(s.params, method_params<CurvatureDistanceParams>("curvature-distance"));
  append(s.params, method_params<LfsParams>("lfs"));
  s.examples = {"pointsurf simplify data/b9_training.ply small.ply --method grid --cell 2",
                "pointsurf simplify data/kitten.xyz kitten_small.ply --method regional --ratio 0.25"};
  s.results = simplify_specs();
  s.run = run_simplify;
  s.check = [](const StageArgs& a) {
    const int given = int(a.given("ratio")) + int(a.given("count")) + int(a.has("cell") && a.given("cell"));
    if (given > 1) throw key_error("ratio", ", count and cell: give only one of them");
    const std::string& m = a.method();
    if (m == "grid") grid_params(a).validate();
    else if (m == "random") random_params(a).validate();
    else if (m == "curvature") curvature_simplify_params(a).validate();
    else if (m == "regional") regional_params(a).validate();
    else if (m == "curvature-distance") curvature_distance_params(a).validate();
    else if (m == "lfs") lfs_params(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
