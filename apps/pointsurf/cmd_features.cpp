// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf features IN OUT: sharp-feature points (edges and corners) into the field "feature".
#include <cmath>
#include <memory>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/feature_points.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct FeaturesState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  FeatureParams params;
  std::string normals = "robust";
  std::string truth_field;
};

FeatureNormals parse_feature_normals(const std::string& name) {
  if (name == "robust") return FeatureNormals::Robust;
  if (name == "input") return FeatureNormals::Input;
  throw UsageError(fmt::format("--normals: '{}': expected robust or input", name));
}

void validate(const FeaturesState& s) {
  const FeatureParams& p = s.params;
  if (p.k < 6) throw UsageError(fmt::format("--k: {} must be at least 6", p.k));
  if (!(p.variation_threshold >= 0.0 && p.variation_threshold < 1.0 / 3.0))
    throw UsageError(fmt::format("--threshold: {} must be in [0, 1/3) (0: derived from the data)", p.variation_threshold));
  if (!(p.dn_deg > 0.0 && p.dn_deg < 90.0)) throw UsageError(fmt::format("--dn: {} must be in (0, 90) degrees", p.dn_deg));
  if (!(p.dd >= 0.0 && std::isfinite(p.dd))) throw UsageError(fmt::format("--dd: {} must be >= 0 (0: from --dd-spacings)", p.dd));
  if (!(p.dd_in_spacings > 0.0 && std::isfinite(p.dd_in_spacings)))
    throw UsageError(fmt::format("--dd-spacings: {} must be positive", p.dd_in_spacings));
  if (p.min_cluster_points < 3 || p.min_cluster_points > p.k)
    throw UsageError(fmt::format("--min-cluster: {} must be in [3, k = {}]", p.min_cluster_points, p.k));
}

// Precision and recall of the labels against a ground-truth field (non-zero = feature point).
nlohmann::json score_against(const std::vector<double>& truth, const std::vector<double>& labels) {
  std::size_t labelled = 0, expected = 0, both = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const bool l = labels[i] != 0.0, t = truth[i] != 0.0;
    labelled += l;
    expected += t;
    both += l && t;
  }
  return {{"truth_points", expected},
          {"precision", labelled == 0 ? 0.0 : double(both) / double(labelled)},
          {"recall", expected == 0 ? 0.0 : double(both) / double(expected)}};
}

void run_features(FeaturesState& s) {
  validate(s);
  s.params.normals = parse_feature_normals(s.normals);
  format_from_extension(s.output_path);  // an unknown output extension fails now, not after the work

  Report report("features");
  report.parameters() = {{"input", s.input},
                         {"output", s.output_path},
                         {"k", s.params.k},
                         {"threshold", s.params.variation_threshold},
                         {"dn_deg", s.params.dn_deg},
                         {"dd", s.params.dd},
                         {"dd_spacings", s.params.dd_in_spacings},
                         {"min_cluster", s.params.min_cluster_points},
                         {"normals", s.normals}};
  if (!s.truth_field.empty()) report.parameters()["truth_field"] = s.truth_field;

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  if (cloud.size() < static_cast<std::size_t>(s.params.k) + 1)
    throw InputError(fmt::format("{}: {} points; feature detection with k = {} needs at least {}", s.input, cloud.size(), s.params.k,
                                 s.params.k + 1));
  const ScalarField* truth = nullptr;
  if (!s.truth_field.empty()) {
    truth = cloud.fields.find(s.truth_field);
    if (truth == nullptr) throw UsageError(fmt::format("--truth-field: '{}': the input has no field of that name", s.truth_field));
  }

  std::size_t stage = report.begin_stage("kdtree");
  const KdTree tree(cloud.positions);
  report.end_stage(stage);

  bool estimated = false;
  if (s.params.normals == FeatureNormals::Input && !cloud.has_normals()) {
    estimate_missing_normals(cloud, tree, s.params.k, s.common, report);
    estimated = true;
  }

  stage = report.begin_stage("features");
  FeatureResult result;
  {
    ProgressBar bar("features", !s.common.quiet);
    result = detect_feature_points(cloud, s.params, &tree, bar.callback());
  }
  report.end_stage(stage);
  report.stage(stage)["counts"] = {{"points", cloud.size()},
                                   {"candidates", result.candidates},
                                   {"edges", result.edges},
                                   {"corners", result.corners}};
  report.stage(stage)["metrics"] = {{"mean_spacing", result.mean_spacing},
                                    {"variation_threshold_used", result.variation_threshold_used},
                                    {"dd_used", result.dd_used}};
  std::string scored;
  if (truth != nullptr) {
    const nlohmann::json score = score_against(truth->values, cloud.fields.find("feature")->values);
    report.stage(stage)["metrics"].update(score);
    scored = fmt::format(", precision {:.3f} recall {:.3f} against '{}'", score["precision"].get<double>(),
                         score["recall"].get<double>(), s.truth_field);
  }
  write_cloud_reported(s.output_path, cloud, s.output, s.common, report);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet)
    fmt::print(stderr, "{} -> {}: {} points, {} candidates, {} edge and {} corner points (threshold {:.4g}, dd {:.4g}){}{}, {:.2f} s\n",
               s.input, s.output_path, cloud.size(), result.candidates, result.edges, result.corners, result.variation_threshold_used,
               result.dd_used, estimated ? ", normals estimated" : "", scored, report.json()["total_seconds"].get<double>());
}

}  // namespace

Command register_features(CLI::App& app) {
  auto state = std::make_shared<FeaturesState>();
  CLI::App* cmd = app.add_subcommand("features", "Sharp-feature points: field 'feature' = 0 none, 1 edge, 2 corner");
  cmd->add_option("input", state->input, "Input cloud")->required();
  cmd->add_option("output", state->output_path, "Output cloud with the field 'feature' (format from the extension)")->required();
  cmd->add_option("--k", state->params.k, "Neighbours per point (default 30)");
  cmd->add_option("--threshold", state->params.variation_threshold,
                  "Candidate surface-variation threshold in [0, 1/3) (default 0: max(0.01, 4 x median variation))")
      ->type_name("S");
  cmd->add_option("--dn", state->params.dn_deg, "Normal-angle clustering threshold, degrees (default 20)")->type_name("DEG");
  cmd->add_option("--dd", state->params.dd, "Point-to-plane distance, cloud units (default 0: --dd-spacings x mean spacing)")
      ->type_name("D");
  cmd->add_option("--dd-spacings", state->params.dd_in_spacings, "Point-to-plane distance in mean spacings when --dd is 0 (default 1)")
      ->type_name("F");
  cmd->add_option("--min-cluster", state->params.min_cluster_points, "Fewest neighbours a cluster needs to give a plane (default 5)");
  cmd->add_option("--normals", state->normals,
                  "Normals to cluster by: robust (flattest shifted neighbourhood, computed) or input (estimated when absent); default robust")
      ->type_name("KIND");
  cmd->add_option("--truth-field", state->truth_field, "Field of the input marking true feature points (non-zero): report precision/recall")
      ->type_name("NAME");
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  cmd->footer("Example: pointsurf features part.ply part_features.ply --report features.json");
  return {cmd, [state] { run_features(*state); }, &state->common};
}

const CommandRegistration features_registration{70, register_features};

}  // namespace pointsurf::cli
