// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf clean IN OUT --method LIST: outlier removal, duplicates and feature-aware denoising,
// applied in the order given.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/clean/remove_duplicates.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/clean/smooth_points.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

enum class Method { Sor, Radius, Ransac, Bilateral, Trilateral, Duplicates };

struct CleanState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  std::string methods = "sor";
  int k = 0;  // 0: each method's default (sor 20, ransac 24)
  double std_ratio = 2.0;
  double radius = 0.0;
  int min_neighbours = 4;
  double distance = 0.0;
  double min_support = 0.3;
  double min_relative_support = RansacOutlierParams{}.min_relative_support;
  int iterations = 2;
  double height_sigma = 0.0;
  double sharpness_deg = 20.0;
  bool exact = false;
  std::uint64_t seed = 1;
  CLI::Option* k_option = nullptr;
};

Method parse_method(const std::string& name) {
  if (name == "sor") return Method::Sor;
  if (name == "radius") return Method::Radius;
  if (name == "ransac") return Method::Ransac;
  if (name == "bilateral") return Method::Bilateral;
  if (name == "trilateral") return Method::Trilateral;
  if (name == "duplicates") return Method::Duplicates;
  throw UsageError(
      fmt::format("--method: '{}': expected sor, radius, ransac, bilateral, trilateral or duplicates (or a comma-separated list)", name));
}

const char* method_name(Method m) {
  switch (m) {
    case Method::Sor: return "sor";
    case Method::Radius: return "radius";
    case Method::Ransac: return "ransac";
    case Method::Bilateral: return "bilateral";
    case Method::Trilateral: return "trilateral";
    case Method::Duplicates: return "duplicates";
  }
  return "";
}

std::vector<Method> parse_methods(const std::string& list) {
  std::vector<Method> out;
  std::stringstream stream(list);
  std::string name;
  while (std::getline(stream, name, ',')) out.push_back(parse_method(ascii_lower(name)));
  if (out.empty()) throw UsageError("--method: expected at least one method");
  return out;
}

void check_length_option(const char* option, double value) {
  if (!(std::isfinite(value) && value >= 0.0))
    throw UsageError(fmt::format("{}: {} must be >= 0 (cloud units; 0: derived from the mean spacing)", option, value));
}

// Validates every option before any file is read, so a typo costs nothing.
void validate(const CleanState& s, const std::vector<Method>& methods) {
  auto uses = [&](Method m) { return std::find(methods.begin(), methods.end(), m) != methods.end(); };
  const bool k_given = s.k_option->count() > 0;
  if (k_given && uses(Method::Ransac) && s.k < 4) throw UsageError(fmt::format("--k: {} must be at least 4 for ransac", s.k));
  if (k_given && s.k < 1) throw UsageError(fmt::format("--k: {} must be at least 1", s.k));
  if (!(std::isfinite(s.std_ratio) && s.std_ratio > 0.0)) throw UsageError(fmt::format("--std-ratio: {} must be > 0", s.std_ratio));
  check_length_option("--radius", s.radius);
  check_length_option("--distance", s.distance);
  check_length_option("--height-sigma", s.height_sigma);
  if (s.min_neighbours < 1) throw UsageError(fmt::format("--min-neighbours: {} must be at least 1", s.min_neighbours));
  if (!(s.min_support > 0.0 && s.min_support <= 1.0))
    throw UsageError(fmt::format("--min-support: {} must be in (0, 1] (a fraction of the neighbourhood)", s.min_support));
  if (!(s.min_relative_support >= 0.0 && s.min_relative_support <= 1.0))
    throw UsageError(fmt::format("--min-relative-support: {} must be in [0, 1]", s.min_relative_support));
  if (s.iterations < 1) throw UsageError(fmt::format("--iterations: {} must be at least 1", s.iterations));
  if (!(s.sharpness_deg > 0.0 && s.sharpness_deg <= 90.0))
    throw UsageError(fmt::format("--sharpness-deg: {} must be in (0, 90] degrees", s.sharpness_deg));
}

void run_clean(const CleanState& s) {
  const std::vector<Method> methods = parse_methods(s.methods);
  validate(s, methods);
  format_from_extension(s.output_path);  // an unknown output extension fails now, not after the work
  const bool k_given = s.k_option->count() > 0;

  Report report("clean");
  report.parameters() = {{"input", s.input},
                         {"output", s.output_path},
                         {"methods", s.methods},
                         {"k", k_given ? nlohmann::json(s.k) : nlohmann::json("default")},
                         {"std_ratio", s.std_ratio},
                         {"radius", s.radius},
                         {"min_neighbours", s.min_neighbours},
                         {"distance", s.distance},
                         {"min_support", s.min_support},
                         {"min_relative_support", s.min_relative_support},
                         {"iterations", s.iterations},
                         {"height_sigma", s.height_sigma},
                         {"sharpness_deg", s.sharpness_deg},
                         {"exact", s.exact},
                         {"seed", s.seed}};

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  const std::size_t input_points = cloud.size();
  std::vector<std::string> summary;
  bool estimated_normals = false;

  for (const Method method : methods) {
    const std::string name = method_name(method);
    if (cloud.size() < 4) throw InputError(fmt::format("{}: {} points left before {}; cleaning needs at least 4", s.input, cloud.size(), name));
    const bool smoothing = method == Method::Bilateral || method == Method::Trilateral;
    const KdTree tree(cloud.positions);  // one tree per step: the previous step may have removed points
    if (smoothing && !cloud.has_normals()) {
      // The filters move points along their normals: estimate and orient them when missing.
      estimate_missing_normals(cloud, tree, NormalParams{}.k, s.common, report);
      estimated_normals = true;
    }

    const std::size_t stage = report.begin_stage(name);
    const std::size_t before = cloud.size();
    nlohmann::json& record = report.stage(stage);
    ProgressBar bar(name, !s.common.quiet);
    auto removal = [&](const OutlierResult& r, const char* threshold_name) {
      cloud = keep_points(cloud, r.kept);
      record["counts"] = {{"input", before}, {"removed", r.removed}, {"kept", r.kept.size()}};
      record["metrics"] = {{threshold_name, r.threshold},
                           {"removed_fraction", before == 0 ? 0.0 : double(r.removed) / double(before)}};
      summary.push_back(fmt::format("{} removed {} ({:.2f}%)", name, r.removed, 100.0 * double(r.removed) / double(before)));
    };
    auto smoothed = [&](const SmoothResult& r) {
      record["counts"] = {{"input", before}, {"moved", r.moved}};
      record["metrics"] = {{"mean_displacement", r.mean_displacement}, {"rms_displacement", r.rms_displacement},
                           {"max_displacement", r.max_displacement}, {"radius_used", r.radius_used},
                           {"height_sigma_used", r.height_sigma_used}};
      summary.push_back(fmt::format("{} moved {} (rms {:.4g}, max {:.4g})", name, r.moved, r.rms_displacement, r.max_displacement));
    };
    BilateralParams bilateral{.radius = s.radius, .height_sigma = s.height_sigma, .iterations = s.iterations};
    switch (method) {
      case Method::Sor:
        removal(remove_statistical_outliers(cloud, {.k = k_given ? s.k : 20, .std_ratio = s.std_ratio}, &tree, bar.callback()),
                "mean_distance_threshold");
        break;
      case Method::Radius:
        removal(remove_radius_outliers(cloud, {.min_neighbours = s.min_neighbours, .radius = s.radius}, &tree, bar.callback()),
                "radius_used");
        break;
      case Method::Ransac:
        removal(remove_ransac_outliers(
                    cloud, {.k = k_given ? s.k : 24, .distance = s.distance, .min_support = s.min_support,
                     .min_relative_support = s.min_relative_support, .seed = s.seed}, &tree,
                    bar.callback()),
                "distance_used");
        break;
      case Method::Duplicates: {
        const DuplicateResult r = remove_duplicates(cloud, {.exact = s.exact, .distance = s.distance}, &tree, bar.callback());
        record["counts"] = {{"input", before}, {"removed", r.removed}, {"kept", r.kept.size()}};
        record["metrics"] = {{"distance_used", r.distance_used}, {"max_merge_distance", r.max_distance}};
        summary.push_back(fmt::format("duplicates merged {} ({})", r.removed, s.exact ? "exact" : fmt::format("within {:.4g}", r.distance_used)));
        break;
      }
      case Method::Bilateral: smoothed(smooth_bilateral(cloud, bilateral, &tree, bar.callback())); break;
      case Method::Trilateral: {
        const bool has_feature = cloud.fields.contains("feature");
        const SmoothResult r =
            smooth_trilateral(cloud, {.position = bilateral, .sharpness_angle_deg = s.sharpness_deg}, &tree, bar.callback());
        smoothed(r);
        record["counts"]["normals_changed"] = r.normals_changed;
        record["metrics"]["mean_normal_change_deg"] = r.mean_normal_change_deg;
        record["metrics"]["used_feature_field"] = has_feature;
        break;
      }
    }
    report.end_stage(stage);
  }

  write_cloud_reported(s.output_path, cloud, s.output, s.common, report);
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet) {
    std::string steps;
    for (const std::string& part : summary) steps += (steps.empty() ? "" : ", ") + part;
    fmt::print(stderr, "{} -> {}: {} -> {} points; {}{}; {:.2f} s\n", s.input, s.output_path, input_points, cloud.size(), steps,
               estimated_normals ? "; normals estimated (PCA k 30, MST) as the input had none" : "",
               report.json()["total_seconds"].get<double>());
  }
}

}  // namespace

Command register_clean(CLI::App& app) {
  auto state = std::make_shared<CleanState>();
  CLI::App* cmd = app.add_subcommand(
      "clean", "Remove outliers and duplicates, denoise (sor, radius, ransac, duplicates, bilateral, trilateral)");
  cmd->add_option("input", state->input, "Input cloud")->required();
  cmd->add_option("output", state->output_path, "Output cloud (format from the extension)")->required();
  cmd->add_option("--method", state->methods,
                  "Comma-separated steps, applied in order: sor (statistical), radius, ransac (local planes), duplicates, "
                  "bilateral, trilateral (default sor)")
      ->type_name("LIST");
  state->k_option = cmd->add_option("--k", state->k, "Neighbours per point: sor (point included, default 20), ransac (default 24)");
  cmd->add_option("--std-ratio", state->std_ratio, "sor: drop points whose mean kNN distance >= mean + RATIO * std (default 2)")
      ->type_name("RATIO");
  cmd->add_option("--radius", state->radius,
                  "radius: search radius; bilateral/trilateral: neighbourhood radius; cloud units (default 4 / 3 mean spacings)")
      ->type_name("R");
  cmd->add_option("--min-neighbours", state->min_neighbours, "radius: keep points with at least M others within R (default 4)")
      ->type_name("M");
  cmd->add_option("--distance", state->distance,
                  "ransac: plane distance (default 1 mean spacing); duplicates: merge distance (default 0.1 mean spacing); cloud units")
      ->type_name("D");
  cmd->add_option("--min-support", state->min_support, "ransac: fraction of the neighbourhood a plane needs, in (0, 1] (default 0.3)");
  cmd->add_option("--min-relative-support", state->min_relative_support,
                  fmt::format("ransac: a plane through the point keeps it when it holds this fraction of the neighbours or scores this "
                              "fraction of the dominant plane, in [0, 1] (default {})",
                              RansacOutlierParams{}.min_relative_support));
  cmd->add_flag("--exact", state->exact, "duplicates: merge only points with identical coordinates");
  cmd->add_option("--iterations", state->iterations, "bilateral/trilateral: position passes (default 2)");
  cmd->add_option("--height-sigma", state->height_sigma, "bilateral/trilateral: range sigma along the normal, cloud units (default 1 mean spacing)")
      ->type_name("S");
  cmd->add_option("--sharpness-deg", state->sharpness_deg, "trilateral: angle sigma between normals, degrees (default 20)")->type_name("DEG");
  cmd->add_option("--seed", state->seed, "ransac: random seed (default 1)");
  add_common_options(*cmd, state->common);
  add_output_options(*cmd, state->output);
  return {cmd, [state] { run_clean(*state); }, &state->common};
}

const CommandRegistration clean_registration{30, register_clean};

}  // namespace pointsurf::cli
