// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf normals IN OUT: PCA normals, oriented (MST by default).
#include <cmath>
#include <memory>
#include <numbers>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct NormalsState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  int k = 30;
  double radius = 0.0;
  std::string orient = "mst";
  std::string viewpoint, direction;
  int orient_k = 10;
  CLI::Option* k_option = nullptr;
};

Orientation parse_orientation(const std::string& name) {
  if (name == "mst") return Orientation::Mst;
  if (name == "viewpoint") return Orientation::Viewpoint;
  if (name == "direction") return Orientation::Direction;
  if (name == "none") return Orientation::None;
  throw UsageError(fmt::format("--orient: '{}': expected mst, viewpoint, direction or none", name));
}

// Angles between estimated normals and normals the input came with: the quality figure when
// the scan carries its own normals.
nlohmann::json compare_normals(const std::vector<Vector3d>& reference, const std::vector<Vector3d>& estimated) {
  double sum_unoriented = 0.0;
  std::size_t agree = 0, used = 0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double nr = reference[i].norm(), ne = estimated[i].norm();
    if (nr == 0.0 || ne == 0.0) continue;
    const double c = reference[i].dot(estimated[i]) / (nr * ne);
    sum_unoriented += std::acos(std::min(1.0, std::abs(c))) * 180.0 / std::numbers::pi;
    agree += c > 0.0;
    ++used;
  }
  if (used == 0) return nlohmann::json::object();
  return {{"input_normals_compared", used},
          {"mean_angle_to_input_deg", sum_unoriented / static_cast<double>(used)},
          {"orientation_agreement_with_input", static_cast<double>(agree) / static_cast<double>(used)}};
}

void run_normals(const NormalsState& s) {
  if (s.k < 3) throw UsageError(fmt::format("--k: {} must be at least 3", s.k));
  if (s.radius < 0.0 || !std::isfinite(s.radius)) throw UsageError(fmt::format("--radius: {} must be positive", s.radius));
  if (s.orient_k < 1) throw UsageError(fmt::format("--orient-k: {} must be at least 1", s.orient_k));
  OrientParams orient;
  orient.method = parse_orientation(s.orient);
  orient.k = s.orient_k;
  if (orient.method == Orientation::Viewpoint) {
    if (s.viewpoint.empty()) throw UsageError("--orient viewpoint needs --viewpoint X,Y,Z");
    orient.viewpoint = parse_vector3(s.viewpoint, "--viewpoint");
  }
  if (orient.method == Orientation::Direction) {
    orient.direction = s.direction.empty() ? Eigen::Vector3d::UnitZ() : parse_vector3(s.direction, "--direction");
    if (orient.direction.norm() == 0.0) throw UsageError("--direction: must not be the zero vector");
  }
  NormalParams params;
  params.k = s.k;
  params.radius = s.radius;
  // --radius alone: radius neighbourhoods; with an explicit --k as well: hybrid (at most k within r).
  if (s.radius > 0.0) params.neighborhood = s.k_option->count() > 0 ? NeighborhoodKind::Hybrid : NeighborhoodKind::Radius;
  format_from_extension(s.output_path);  // an unknown output extension fails now, not after the work

  Report report("normals");
  report.parameters() = {{"input", s.input},
                         {"output", s.output_path},
                         {"k", s.k},
                         {"radius", s.radius},
                         {"neighborhood", params.neighborhood == NeighborhoodKind::Knn      ? "knn"
                                          : params.neighborhood == NeighborhoodKind::Radius ? "radius"
                                                                                            : "hybrid"},
                         {"orient", s.orient},
                         {"orient_k", s.orient_k}};
  if (orient.method == Orientation::Viewpoint) report.parameters()["viewpoint"] = {orient.viewpoint.x(), orient.viewpoint.y(), orient.viewpoint.z()};
  if (orient.method == Orientation::Direction) report.parameters()["direction"] = {orient.direction.x(), orient.direction.y(), orient.direction.z()};

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  if (cloud.size() < 3) throw InputError(fmt::format("{}: {} points; normals need at least 3", s.input, cloud.size()));
  std::vector<Vector3d> input_normals;
  std::swap(input_normals, cloud.normals);  // estimate from scratch; compare afterwards

  std::size_t stage = report.begin_stage("kdtree");
  const KdTree tree(cloud.positions);
  const double spacing = mean_spacing(tree);
  report.end_stage(stage);
  report.stage(stage)["metrics"]["mean_spacing"] = spacing;

  stage = report.begin_stage("normals");
  NormalResult estimated;
  {
    ProgressBar bar("normals", !s.common.quiet);
    estimated = estimate_normals(cloud, params, &tree, bar.callback());
  }
  report.end_stage(stage);
  report.stage(stage)["counts"] = {{"points", cloud.size()}, {"degenerate", estimated.degenerate}};
  if (params.neighborhood != NeighborhoodKind::Knn) report.stage(stage)["metrics"]["radius_used"] = estimated.radius_used;
  if (estimated.degenerate > 0)
    report.warn(fmt::format("{} points have fewer than 3 neighbours or a degenerate neighbourhood: normal (0,0,0)", estimated.degenerate),
                s.common.quiet);

  if (orient.method != Orientation::None) {
    stage = report.begin_stage("orient");
    OrientResult oriented;
    {
      ProgressBar bar("orient", !s.common.quiet);
      oriented = orient_normals(cloud, orient, &tree, bar.callback());
    }
    report.end_stage(stage);
    report.stage(stage)["counts"] = {{"flipped", oriented.flipped}, {"components", oriented.components}};
  }
  if (!input_normals.empty()) {
    nlohmann::json metrics = compare_normals(input_normals, cloud.normals);
    report.stage(report.json()["stages"].size() - 1)["metrics"].update(metrics);
  }
  write_cloud_reported(s.output_path, cloud, s.output, s.common, report);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet)
    fmt::print(stderr, "{} -> {}: {} normals (k {}, mean spacing {:.4g}), orientation {}, {:.2f} s\n", s.input, s.output_path,
               cloud.size(), s.k, spacing, s.orient, report.json()["total_seconds"].get<double>());
}

}  // namespace

Command register_normals(CLI::App& app) {
  auto state = std::make_shared<NormalsState>();
  CLI::App* cmd = app.add_subcommand("normals", "Estimate normals by PCA and orient them (MST propagation by default)");
  cmd->add_option("input", state->input, "Input cloud")->required();
  cmd->add_option("output", state->output_path, "Output cloud with normals (format from the extension)")->required();
  state->k_option = cmd->add_option("--k", state->k, "Neighbours per point (default 30; with --radius: at most k within r)");
  cmd->add_option("--radius", state->radius, "Neighbourhood radius in cloud units (radius search instead of kNN)")->type_name("R");
  cmd->add_option("--orient", state->orient, "Orientation: mst (consistent, Hoppe 1992), viewpoint, direction or none (default mst)")
      ->type_name("METHOD");
  cmd->add_option("--viewpoint", state->viewpoint, "Scanner position for --orient viewpoint")->type_name("X,Y,Z");
  cmd->add_option("--direction", state->direction, "Direction normals should face for --orient direction (default 0,0,1)")
      ->type_name("X,Y,Z");
  cmd->add_option("--orient-k", state->orient_k, "Neighbours per point in the MST graph (default 10)");
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  return {cmd, [state] { run_normals(*state); }, &state->common};
}

const CommandRegistration normals_registration{50, register_normals};

}  // namespace pointsurf::cli
