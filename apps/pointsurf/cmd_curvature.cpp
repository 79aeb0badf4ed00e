// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf curvature IN OUT: jet-fit principal curvatures, H, K, surface variation and the
// HK surface type of every point.
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/shape/curvature.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct CurvatureState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  int degree = 2;
  int k = 0;
  double radius = 0.0;
  double zero_curvature = 0.0;
  int normal_k = 30;
  bool update_normals = false;
  CLI::Option* k_option = nullptr;
};

void run_curvature(const CurvatureState& s) {
  if (s.degree != 2 && s.degree != 3) throw UsageError(fmt::format("--degree: {} must be 2 or 3", s.degree));
  const int min_k = s.degree == 2 ? 6 : 10;
  if (s.k_option->count() > 0 && s.k < min_k)
    throw UsageError(fmt::format("--k: {} must be at least {} for degree {}", s.k, min_k, s.degree));
  if (!(s.radius >= 0.0) || !std::isfinite(s.radius)) throw UsageError(fmt::format("--radius: {} must be positive", s.radius));
  if (!(s.zero_curvature >= 0.0) || !std::isfinite(s.zero_curvature))
    throw UsageError(fmt::format("--zero-curvature: {} must be >= 0 (1/cloud units; 0 derives it from the data)", s.zero_curvature));
  if (s.normal_k < 3) throw UsageError(fmt::format("--normal-k: {} must be at least 3", s.normal_k));
  CurvatureParams params;
  params.degree = s.degree;
  params.k = s.k_option->count() > 0 ? s.k : 0;
  params.radius = s.radius;
  params.zero_curvature = s.zero_curvature;
  params.update_normals = s.update_normals;
  // --radius alone: radius neighbourhoods; with an explicit --k as well: hybrid (at most k within r).
  if (s.radius > 0.0) params.neighborhood = s.k_option->count() > 0 ? NeighborhoodKind::Hybrid : NeighborhoodKind::Radius;
  format_from_extension(s.output_path);  // an unknown output extension fails now, not after the work

  Report report("curvature");
  report.parameters() = {{"input", s.input},
                         {"output", s.output_path},
                         {"degree", s.degree},
                         {"k", params.k},
                         {"radius", s.radius},
                         {"neighborhood", params.neighborhood == NeighborhoodKind::Knn      ? "knn"
                                          : params.neighborhood == NeighborhoodKind::Radius ? "radius"
                                                                                            : "hybrid"},
                         {"zero_curvature", s.zero_curvature},
                         {"normal_k", s.normal_k},
                         {"update_normals", s.update_normals}};

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  const std::size_t needed = s.degree == 2 ? 6 : 10;
  if (cloud.size() < needed)
    throw InputError(fmt::format("{}: {} points; a degree-{} jet needs at least {}", s.input, cloud.size(), s.degree, needed));

  std::size_t stage = report.begin_stage("kdtree");
  const KdTree tree(cloud.positions);
  const double spacing = mean_spacing(tree);
  report.end_stage(stage);
  report.stage(stage)["metrics"]["mean_spacing"] = spacing;

  // The sign of the curvature comes from the normals: estimate and orient them when missing.
  const bool estimated_normals = !cloud.has_normals();
  if (estimated_normals) estimate_missing_normals(cloud, tree, s.normal_k, s.common, report);

  stage = report.begin_stage("curvature");
  CurvatureResult result;
  {
    ProgressBar bar("curvature", !s.common.quiet);
    result = estimate_curvature(cloud, params, &tree, bar.callback());
  }
  report.end_stage(stage);
  nlohmann::json counts = {{"points", cloud.size()}, {"degenerate", result.degenerate}};
  for (int t = 0; t < kSurfaceTypeCount; ++t)
    counts[surface_type_name(static_cast<SurfaceType>(t))] = result.type_counts[std::size_t(t)];
  report.stage(stage)["counts"] = counts;
  nlohmann::json& metrics = report.stage(stage)["metrics"];
  metrics["zero_curvature"] = result.zero_curvature;
  metrics["median_residual"] = result.median_residual;
  if (params.neighborhood != NeighborhoodKind::Radius) metrics["k_used"] = result.k_used;
  if (params.neighborhood != NeighborhoodKind::Knn) metrics["radius_used"] = result.radius_used;
  if (result.degenerate > 0)
    report.warn(fmt::format("{} points have a zero normal, too few neighbours or a singular jet fit: curvature 0, "
                            "surface_type 0 (undefined)",
                            result.degenerate),
                s.common.quiet);

  write_cloud_reported(s.output_path, cloud, s.output, s.common, report);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet) {
    std::size_t best = 1;
    for (std::size_t t = 2; t < result.type_counts.size(); ++t)
      if (result.type_counts[t] > result.type_counts[best]) best = t;
    fmt::print(stderr, "{} -> {}: curvature of {} points (degree {}, {}{}), zero at {:.3g}, mostly {} ({:.1f} %), {} degenerate, {:.2f} s\n",
               s.input, s.output_path, cloud.size(), s.degree,
               params.neighborhood == NeighborhoodKind::Radius ? fmt::format("radius {:.4g}", result.radius_used)
                                                               : fmt::format("k {}", result.k_used),
               estimated_normals ? ", normals estimated and oriented" : "", result.zero_curvature,
               surface_type_name(static_cast<SurfaceType>(best)),
               100.0 * double(result.type_counts[best]) / double(std::max<std::size_t>(cloud.size(), 1)), result.degenerate,
               report.json()["total_seconds"].get<double>());
  }
}

}  // namespace

Command register_curvature(CLI::App& app) {
  auto state = std::make_shared<CurvatureState>();
  CLI::App* cmd = app.add_subcommand(
      "curvature", "Principal curvatures k1 >= k2, mean H, Gaussian K, surface variation and HK surface type by jet fitting");
  cmd->add_option("input", state->input, "Input cloud (normals are estimated and oriented when absent)")->required();
  cmd->add_option("output", state->output_path,
                  "Output cloud with fields k1 k2 mean gauss variation surface_type (format from the extension)")
      ->required();
  cmd->add_option("--degree", state->degree, "Jet degree, 2 or 3 (default 2)");
  state->k_option = cmd->add_option("--k", state->k, "Neighbours per point (default 24 for degree 2, 40 for degree 3; with --radius: at most k within r)");
  cmd->add_option("--radius", state->radius, "Neighbourhood radius in cloud units (radius search instead of kNN)")->type_name("R");
  cmd->add_option("--zero-curvature", state->zero_curvature,
                  "Curvature magnitude (1/cloud units) below which H or a principal curvature counts as zero in the surface "
                  "type (default: derived from the fit residuals)")
      ->type_name("Z");
  cmd->add_option("--normal-k", state->normal_k, "Neighbours for normal estimation when the input has none (default 30)");
  cmd->add_flag("--update-normals", state->update_normals, "Write the jet (Monge) normals instead of the input ones");
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  return {cmd, [state] { run_curvature(*state); }, &state->common};
}

const CommandRegistration curvature_registration{60, register_curvature};

}  // namespace pointsurf::cli
