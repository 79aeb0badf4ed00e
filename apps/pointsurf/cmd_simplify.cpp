// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf simplify IN OUT --method M (--ratio F | --count N | --cell S): fewer points
// (or, for lfs, resampled points) that keep the surface.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/simplify/simplify.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct SimplifyState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  std::string method = "grid";
  double ratio = 0.1;
  long long count = 0;
  double cell = 0.0;
  std::string mode = "centroid";
  int k = 16;
  unsigned long long seed = 42;
  double region = 10.0;
  double region_angle = 30.0;
  double feature_threshold = -1.0;
  double split_quantile = 0.9;
  double high_to_low = 0.4;
  double adaptivity = 4.0;
  CLI::Option* ratio_option = nullptr;
  CLI::Option* count_option = nullptr;
  CLI::Option* cell_option = nullptr;
};

const char* const kMethods = "grid, random, curvature, regional, curvature-distance or lfs";

SimplifyTarget parse_target(const SimplifyState& s) {
  const std::size_t given = s.ratio_option->count() + s.count_option->count() + s.cell_option->count();
  if (given > 1) throw UsageError("--ratio, --count and --cell: give only one of them");
  SimplifyTarget target;
  if (s.cell_option->count() > 0) {
    if (!(s.cell > 0.0) || !std::isfinite(s.cell)) throw UsageError(fmt::format("--cell: {} must be a positive length", s.cell));
    target.cell = s.cell;
  } else if (s.count_option->count() > 0) {
    if (s.count < 1) throw UsageError(fmt::format("--count: {} must be at least 1", s.count));
    target.count = static_cast<std::size_t>(s.count);
  } else {
    if (!(s.ratio > 0.0 && s.ratio <= 1.0)) throw UsageError(fmt::format("--ratio: {} must be in (0, 1]", s.ratio));
    target.ratio = s.ratio;
  }
  return target;
}

void run_simplify(const SimplifyState& s) {
  static const std::vector<std::string> methods = {"grid", "random", "curvature", "regional", "curvature-distance", "lfs"};
  if (std::find(methods.begin(), methods.end(), s.method) == methods.end())
    throw UsageError(fmt::format("--method: '{}': expected {}", s.method, kMethods));
  const SimplifyTarget target = parse_target(s);
  if ((s.method == "random" || s.method == "curvature") && target.cell > 0.0)
    throw UsageError(fmt::format("--cell: --method {} takes --ratio or --count", s.method));
  if (s.mode != "centroid" && s.mode != "nearest") throw UsageError(fmt::format("--mode: '{}': expected centroid or nearest", s.mode));
  if (s.k < 3) throw UsageError(fmt::format("--k: {} must be at least 3", s.k));
  if (!(s.region > 0.0) || !std::isfinite(s.region)) throw UsageError(fmt::format("--region: {} must be positive (mean spacings)", s.region));
  if (!(s.region_angle > 0.0 && s.region_angle <= 90.0)) throw UsageError(fmt::format("--region-angle: {} must be in (0, 90] degrees", s.region_angle));
  if (!(s.feature_threshold <= 1.0)) throw UsageError(fmt::format("--feature-threshold: {} must be in [0, 1] (or negative: derived)", s.feature_threshold));
  if (!(s.split_quantile > 0.0 && s.split_quantile < 1.0)) throw UsageError(fmt::format("--split-quantile: {} must be in (0, 1)", s.split_quantile));
  if (!(s.high_to_low > 0.0 && s.high_to_low <= 1.0)) throw UsageError(fmt::format("--high-to-low: {} must be in (0, 1]", s.high_to_low));
  if (!(s.adaptivity >= 1.0) || !std::isfinite(s.adaptivity)) throw UsageError(fmt::format("--adaptivity: {} must be at least 1", s.adaptivity));
  format_from_extension(s.output_path);  // an unknown output extension fails now, not after the work

  Report report("simplify");
  report.parameters() = {{"input", s.input}, {"output", s.output_path}, {"method", s.method}, {"k", s.k}};
  if (target.cell > 0.0) report.parameters()["cell"] = target.cell;
  else if (target.count > 0) report.parameters()["count"] = target.count;
  else report.parameters()["ratio"] = target.ratio;
  if (s.method == "grid") report.parameters()["mode"] = s.mode;
  if (s.method == "random" || s.method == "curvature") report.parameters()["seed"] = s.seed;
  if (s.method == "regional") {
    report.parameters()["region_in_spacings"] = s.region;
    report.parameters()["region_angle_deg"] = s.region_angle;
    report.parameters()["feature_threshold"] = s.feature_threshold;
  }
  if (s.method == "curvature-distance") {
    report.parameters()["split_quantile"] = s.split_quantile;
    report.parameters()["high_to_low_distance"] = s.high_to_low;
  }
  if (s.method == "lfs") report.parameters()["adaptivity"] = s.adaptivity;

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  if (cloud.empty()) throw InputError(fmt::format("{}: no points", s.input));
  const bool surface_method = s.method != "grid" && s.method != "random";
  if (surface_method && cloud.size() < 3)
    throw InputError(fmt::format("{}: {} points; --method {} needs at least 3", s.input, cloud.size(), s.method));

  std::optional<KdTree> tree;
  double spacing = 0.0;
  if (surface_method || cloud.size() >= 2) {
    const std::size_t stage = report.begin_stage("kdtree");
    tree.emplace(cloud.positions);
    spacing = cloud.size() >= 2 ? mean_spacing(*tree) : 0.0;
    report.end_stage(stage);
    report.stage(stage)["metrics"]["mean_spacing"] = spacing;
  }

  // Methods that use curvature or normals: estimate them once here (and orient new normals), so
  // that the output carries them and the report shows the stage.
  bool estimated_normals = false;
  const bool needs_normals = s.method == "regional" || s.method == "lfs";
  if (surface_method && (!cloud.fields.contains("variation") || (needs_normals && !cloud.has_normals()))) {
    std::size_t stage = report.begin_stage("normals");
    PointCloud work;
    work.positions = cloud.positions;
    NormalParams params;
    params.k = s.k;
    NormalResult estimated;
    {
      ProgressBar bar("normals", !s.common.quiet);
      estimated = estimate_normals(work, params, &*tree, bar.callback());
    }
    report.end_stage(stage);
    report.stage(stage)["counts"] = {{"points", cloud.size()}, {"degenerate", estimated.degenerate}};
    ScalarField& variation = cloud.fields.add("variation", 0, ScalarType::Float32);
    variation = std::move(*work.fields.find("variation"));
    if (!cloud.has_normals()) {
      estimated_normals = true;
      cloud.normals = std::move(work.normals);
      stage = report.begin_stage("orient");
      OrientResult oriented;
      {
        ProgressBar bar("orient", !s.common.quiet);
        oriented = orient_normals(cloud, {}, &*tree, bar.callback());
      }
      report.end_stage(stage);
      report.stage(stage)["counts"] = {{"flipped", oriented.flipped}, {"components", oriented.components}};
    }
  }

  const std::size_t stage = report.begin_stage("simplify");
  SimplifyResult result;
  {
    ProgressBar bar("simplify", !s.common.quiet);
    const ProgressCallback progress = bar.callback();
    const KdTree* t = tree ? &*tree : nullptr;
    if (s.method == "grid") {
      GridParams p{target, s.mode == "nearest" ? GridMode::Nearest : GridMode::Centroid};
      result = simplify_grid(cloud, p, progress);
    } else if (s.method == "random") {
      result = simplify_random(cloud, RandomParams{target, s.seed});
    } else if (s.method == "curvature") {
      CurvatureParams p;
      p.target = target;
      p.k = s.k;
      p.seed = s.seed;
      result = simplify_curvature(cloud, p, t, progress);
    } else if (s.method == "regional") {
      RegionalParams p;
      p.target = target;
      p.k = s.k;
      p.region_in_spacings = s.region;
      p.region_angle_deg = s.region_angle;
      p.feature_threshold = s.feature_threshold;
      result = simplify_regional(cloud, p, t, progress);
    } else if (s.method == "curvature-distance") {
      CurvatureDistanceParams p;
      p.target = target;
      p.k = s.k;
      p.split_quantile = s.split_quantile;
      p.high_to_low_distance = s.high_to_low;
      result = simplify_curvature_distance(cloud, p, t, progress);
    } else {
      LfsParams p;
      p.target = target;
      p.k = s.k;
      p.adaptivity = s.adaptivity;
      result = resample_lfs(cloud, p, t, progress);
    }
  }
  report.end_stage(stage);
  const std::size_t kept_inputs = result.cloud.size() - result.added_points;
  report.stage(stage)["counts"] = {{"input", cloud.size()},           {"output", result.cloud.size()},
                                   {"removed", cloud.size() - kept_inputs}, {"feature_points", result.feature_points},
                                   {"added", result.added_points}};
  nlohmann::json& metrics = report.stage(stage)["metrics"];
  metrics["reduction"] = result.reduction();
  if (result.length_used > 0.0) metrics["length_used"] = result.length_used;
  // How far the simplified cloud is from the full one, both ways: the input's distance to the
  // nearest output point (coverage of what was removed) and the output's distance to the nearest
  // input point (how far averaged or inserted points moved).
  if (!result.cloud.empty() && tree) {
    const KdTree out_tree(result.cloud.positions);
    const NeighborLists to_out = out_tree.knn_all(cloud.positions, 1);
    const NeighborLists to_in = tree->knn_all(result.cloud.positions, 1);
    const auto summarise = [](const NeighborLists& lists) {
      double sum = 0.0, worst = 0.0;
      for (const Neighbor& nb : lists.neighbors) {
        const double d = std::sqrt(nb.squared_distance);
        sum += d;
        worst = std::max(worst, d);
      }
      return std::pair{sum / double(std::max<std::size_t>(lists.neighbors.size(), 1)), worst};
    };
    const auto [mean_in, max_in] = summarise(to_out);
    const auto [mean_out, max_out] = summarise(to_in);
    metrics["input_to_output_mean"] = mean_in;
    metrics["input_to_output_max"] = max_in;
    metrics["output_to_input_mean"] = mean_out;
    metrics["output_to_input_max"] = max_out;
    metrics["chamfer"] = 0.5 * (mean_in + mean_out);
    metrics["hausdorff"] = std::max(max_in, max_out);
    if (spacing > 0.0) metrics["chamfer_in_spacings"] = 0.5 * (mean_in + mean_out) / spacing;
  }
  write_cloud_reported(s.output_path, result.cloud, s.output, s.common, report);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet) {
    std::string extra;
    if (result.feature_points > 0) extra += fmt::format(", {} feature points kept", result.feature_points);
    if (result.added_points > 0) extra += fmt::format(", {} points added", result.added_points);
    if (estimated_normals) extra += ", normals estimated (none in the input)";
    fmt::print(stderr, "{} -> {}: {} -> {} points ({}, {:.2f}x){}, {:.2f} s\n", s.input, s.output_path, cloud.size(),
               result.cloud.size(), s.method, result.reduction(), extra, report.json()["total_seconds"].get<double>());
  }
}

}  // namespace

Command register_simplify(CLI::App& app) {
  auto state = std::make_shared<SimplifyState>();
  CLI::App* cmd = app.add_subcommand("simplify", "Simplify a cloud: grid, random, curvature, regional, curvature-distance or LFS resampling");
  cmd->add_option("input", state->input, "Input cloud")->required();
  cmd->add_option("output", state->output_path, "Output cloud (format from the extension)")->required();
  cmd->add_option("--method", state->method, std::string("Method: ") + kMethods + " (default grid)")->type_name("METHOD");
  state->ratio_option = cmd->add_option("--ratio", state->ratio, "Kept fraction of the points, (0, 1] (default 0.1)")->type_name("F");
  state->count_option = cmd->add_option("--count", state->count, "Number of output points (instead of --ratio)")->type_name("N");
  state->cell_option = cmd->add_option("--cell", state->cell,
                                       "Length in cloud units instead of a count: grid cell; Poisson-disk distance of flat points "
                                       "(regional, curvature-distance); spacing at the median feature size (lfs)")
                           ->type_name("S");
  cmd->add_option("--mode", state->mode, "grid: centroid (average each cell) or nearest (keep the sample nearest to it)")->type_name("MODE");
  cmd->add_option("--k", state->k, "Neighbours for normals and curvature when the input has none (default 16)");
  cmd->add_option("--seed", state->seed, "Random seed (random, curvature; default 42)");
  cmd->add_option("--region", state->region, "regional: cluster cell size in mean spacings (default 10)")->type_name("SPACINGS");
  cmd->add_option("--region-angle", state->region_angle, "regional: normal angle joining a cluster, degrees (default 30)")->type_name("DEG");
  cmd->add_option("--feature-threshold", state->feature_threshold,
                  "regional: feature factor threshold in [0, 1] (default: median + 3 MAD of the factor)")
      ->type_name("F");
  cmd->add_option("--split-quantile", state->split_quantile, "curvature-distance: variation quantile splitting high from low (default 0.9)")
      ->type_name("Q");
  cmd->add_option("--high-to-low", state->high_to_low, "curvature-distance: high-part distance / low-part distance, (0, 1] (default 0.4)")
      ->type_name("R");
  cmd->add_option("--adaptivity", state->adaptivity, "lfs: feature size clamped to [median/A, median*A] (default 4)")->type_name("A");
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  return {cmd, [state] { run_simplify(*state); }, &state->common};
}

const CommandRegistration simplify_registration{40, register_simplify};

}  // namespace pointsurf::cli
