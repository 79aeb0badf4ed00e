// SPDX-License-Identifier: GPL-3.0-or-later
// The simplify stage: six methods, one target (ratio, count or cell).
#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/simplify/simplify.h"

namespace pointsurf::detail {
namespace {

SimplifyTarget target_of(const StageArgs& a) {
  SimplifyTarget t;
  t.ratio = a.number("ratio");
  t.count = static_cast<std::size_t>(a.integer("count"));
  if (a.has("cell")) t.cell = a.number("cell");
  return t;
}

CurvatureSimplifyParams curvature_simplify_params(const StageArgs& a) {
  CurvatureSimplifyParams p;
  p.target = target_of(a);
  p.k = a.int32("k");
  p.flat_weight = a.number("flat_weight");
  p.seed = static_cast<std::uint64_t>(a.integer("seed"));
  return p;
}

RegionalParams regional_params(const StageArgs& a) {
  RegionalParams p;
  p.target = target_of(a);
  p.k = a.int32("k");
  p.region_in_spacings = a.number("region_in_spacings");
  p.region_angle_deg = a.number("region_angle_deg");
  p.variation_weight = a.number("variation_weight");
  p.normal_weight = a.number("normal_weight");
  p.distance_weight = a.number("distance_weight");
  p.feature_threshold = a.number("feature_threshold");
  p.max_feature_share = a.number("max_feature_share");
  p.keep_boundary = a.boolean("keep_boundary");
  return p;
}

CurvatureDistanceParams curvature_distance_params(const StageArgs& a) {
  CurvatureDistanceParams p;
  p.target = target_of(a);
  p.k = a.int32("k");
  p.split_quantile = a.number("split_quantile");
  p.high_to_low_distance = a.number("high_to_low_distance");
  return p;
}

LfsParams lfs_params(const StageArgs& a) {
  LfsParams p;
  p.target = target_of(a);
  p.k = a.int32("k");
  p.adaptivity = a.number("adaptivity");
  p.fill_neighbours = a.int32("fill_neighbours");
  return p;
}

void run_simplify(StageRun& run) {
  const StageArgs& a = run.args;
  const std::string& method = a.method();
  DataItem& item = run.context.item(run.output);
  const PointCloud& cloud = item.cloud;
  const bool surface = method != "grid" && method != "random";
  if (surface && cloud.size() < 3) throw InputError(fmt::format("{}; method {} needs at least 3", plural(cloud.size(), "point"), method));
  const SimplifyTarget target = target_of(a);
  const KdTree* tree = cloud.size() >= 2 ? &run.context.tree(run.output) : nullptr;
  const double spacing = cloud.size() >= 2 ? run.context.mean_spacing(run.output) : 0.0;
  const ProgressCallback progress = sub_progress(run.progress, 0.0, 0.9);
  SimplifyResult r;
  if (method == "grid") {
    r = simplify_grid(cloud, {target, a.text("mode") == "nearest" ? GridMode::Nearest : GridMode::Centroid}, progress);
  } else if (method == "random") {
    r = simplify_random(cloud, {target, static_cast<std::uint64_t>(a.integer("seed"))});
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
  rec.count("input", as_count(input));
  rec.count("output", as_count(r.cloud.size()));
  rec.count("removed", as_count(input - kept_inputs));
  rec.count("feature_points", as_count(r.feature_points));
  rec.count("boundary_points", as_count(r.boundary_points));
  rec.count("added", as_count(r.added_points));
  rec.metric("reduction", reduction);
  if (r.length_used > 0.0) rec.metric("length_used", r.length_used);
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
  std::vector<Vector3d> input_positions = std::move(item.cloud.positions);
  if (!item.triangles.empty() || item.is_mesh) drop_faces(item, rec);
  item.cloud = std::move(r.cloud);
  if (tree != nullptr && !item.cloud.empty()) {
    const auto in_to_out = summarise(run.context.tree(run.output).knn_all(input_positions, 1));
    rec.metric("input_to_output_mean", in_to_out.first);
    rec.metric("input_to_output_max", in_to_out.second);
    rec.metric("output_to_input_mean", out_to_in.first);
    rec.metric("output_to_input_max", out_to_in.second);
    rec.metric("chamfer", 0.5 * (in_to_out.first + out_to_in.first));
    rec.metric("hausdorff", std::max(in_to_out.second, out_to_in.second));
    if (spacing > 0.0) rec.metric("chamfer_in_spacings", 0.5 * (in_to_out.first + out_to_in.first) / spacing);
  }
  run.progress ? (void)run.progress(1.0) : (void)0;
  std::string extra;
  if (r.feature_points > 0) extra += fmt::format(", {} kept", plural(r.feature_points, "feature point"));
  if (r.added_points > 0) extra += fmt::format(", {} added", plural(r.added_points, "point"));
  rec.summary = fmt::format("simplify: {} -> {} ({}, {:.2f}x){}", plural(input, "point"), plural(item.cloud.size(), "point"), method,
                            reduction, extra);
}

}  // namespace

StageSpec simplify_stage() {
  const SimplifyTarget t;
  const GridParams grid;
  const RandomParams random;
  const CurvatureSimplifyParams curv;
  const RegionalParams reg;
  const CurvatureDistanceParams cd;
  const LfsParams lfs;
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
  s.params = {
      P::number("ratio", t.ratio, "Kept fraction of the points").range(0.0, 1.0, true, false).meta("F"),
      P::integer("count", static_cast<std::int64_t>(t.count), "Number of output points instead of ratio; 0: use ratio").at_least(0),
      P::number("cell", t.cell,
                "Length instead of a count: grid cell; Poisson-disk distance of flat points (regional, curvature-distance); "
                "spacing at the median feature size (lfs)")
          .unit("cloud units")
          .non_negative()
          .meta("S")
          .only(with_cell),
      P::choice("mode", grid.mode == GridMode::Centroid ? "centroid" : "nearest", {"centroid", "nearest"},
                "centroid (average each cell) or nearest (keep the sample nearest to it)")
          .only({"grid"}),
      P::integer("seed", static_cast<std::int64_t>(random.seed), "Random seed").at_least(0).only({"random"}),
      P::integer("seed", static_cast<std::int64_t>(curv.seed), "Random seed").at_least(0).only({"curvature"}),
      P::integer("k", curv.k, "Neighbours for normals and variation when the input has none").at_least(3).only({"curvature"}),
      P::number("flat_weight", curv.flat_weight, "Weight of a flat point relative to the mean variation").non_negative().only({"curvature"}),
      P::integer("k", reg.k, "Neighbours for normals and variation when the input has none").at_least(3).only({"regional"}),
      P::number("region_in_spacings", reg.region_in_spacings, "Cluster cell size").unit("mean spacings").positive().only({"regional"}),
      P::number("region_angle_deg", reg.region_angle_deg, "Normal angle joining a cluster").unit("degrees").range(0.0, 90.0, true, false).only(
          {"regional"}),
      P::number("variation_weight", reg.variation_weight, "Weight of the surface variation in the feature factor").non_negative().only({"regional"}),
      P::number("normal_weight", reg.normal_weight, "Weight of the normal deviation in the feature factor").non_negative().only({"regional"}),
      P::number("distance_weight", reg.distance_weight, "Weight of the plane distance in the feature factor").non_negative().only({"regional"}),
      P::number("feature_threshold", reg.feature_threshold, "Feature factor above which a point is a candidate, [0, 1]; < 0: derived")
          .range(-std::numeric_limits<double>::infinity(), 1.0)
          .only({"regional"}),
      P::number("max_feature_share", reg.max_feature_share, "At most this share of the output are feature points").range(0.0, 1.0, true, false).only(
          {"regional"}),
      P::boolean("keep_boundary", reg.keep_boundary, "Thin the rims of open surfaces (angular-gap test) on a grid of half the cell").only({"regional"}),
      P::integer("k", cd.k, "Neighbours for variation when the input has none").at_least(3).only({"curvature-distance"}),
      P::number("split_quantile", cd.split_quantile, "Variation quantile splitting high from low").range(0.0, 1.0, true, true).only(
          {"curvature-distance"}),
      P::number("high_to_low_distance", cd.high_to_low_distance, "High-part distance / low-part distance").range(0.0, 1.0, true, false).only(
          {"curvature-distance"}),
      P::integer("k", lfs.k, "Neighbours for normals, variation and feature size").at_least(3).only({"lfs"}),
      P::number("adaptivity", lfs.adaptivity, "Feature size clamped to [median/a, median*a]").at_least(1.0).only({"lfs"}),
      P::integer("fill_neighbours", lfs.fill_neighbours, "kNN edges tested for gaps when filling").at_least(1).only({"lfs"}),
  };
  s.examples = {"pointsurf simplify scan.ply small.ply --method grid --cell 0.05",
                "pointsurf simplify part.ply part_small.ply --method regional --ratio 0.25"};
  s.run = run_simplify;
  s.check = [](const StageArgs& a) {
    const int given = int(a.given("ratio")) + int(a.given("count")) + int(a.has("cell") && a.given("cell"));
    if (given > 1) throw UsageError("ratio, count and cell: give only one of them");
    const std::string& m = a.method();
    if (m == "curvature") curvature_simplify_params(a).validate();
    else if (m == "regional") regional_params(a).validate();
    else if (m == "curvature-distance") curvature_distance_params(a).validate();
    else if (m == "lfs") lfs_params(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
