// SPDX-License-Identifier: GPL-3.0-or-later
// The clean stage: outlier removal, duplicates and feature-aware denoising, applied in the
// order of its method list.
#include <cmath>
#include <string>
#include <vector>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/clean/remove_duplicates.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/clean/smooth_points.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/pipeline/context.h"

namespace pointsurf::detail {
namespace {

// The library's Params of each method from its arguments: the run and the check before any
// work build them the same way, and the check calls their validate().
BilateralParams bilateral_params(const StageArgs& a) { return read_params<BilateralParams>(a); }
LocalOutlierParams local_params(const StageArgs& a) { return read_params<LocalOutlierParams>(a); }
StatisticalOutlierParams sor_params(const StageArgs& a) { return read_params<StatisticalOutlierParams>(a); }
RadiusOutlierParams radius_params(const StageArgs& a) { return read_params<RadiusOutlierParams>(a); }
RansacOutlierParams ransac_params(const StageArgs& a) { return read_params<RansacOutlierParams>(a); }
DuplicateParams duplicate_params(const StageArgs& a) { return read_params<DuplicateParams>(a); }
TrilateralParams trilateral_params(const StageArgs& a) { return read_params<TrilateralParams>(a); }

// The trilateral method's own parameters: those of its position pass are the bilateral
// method's, declared once for both.
std::vector<ParamSpec> trilateral_only_params() {
  std::vector<ParamSpec> out;
  for (ParamSpec& p : params_of(TrilateralParams::fields(), {"trilateral"}))
    if (BilateralParams::fields().find(p.name) == nullptr) out.push_back(std::move(p));
  return out;
}

// What clean reports, each method's values under "<method>.": an outlier removal's count and
// threshold (its key says what the threshold is), a duplicate merge's, a smoothing's moves; then
// the points read and left.
struct CleanCounts {
  std::size_t input = 0, output = 0;
};
const ResultTable<CleanCounts>& clean_counts() {
  static const ResultTable<CleanCounts> table = [] {
    ResultTable<CleanCounts> t;
    t.count("input", &CleanCounts::input, "Points read");
    t.count("output", &CleanCounts::output, "Points left");
    return t;
  }();
  return table;
}

std::vector<ResultSpec> clean_specs() {
  std::vector<ResultSpec> out;
  for (const std::string method : {"local", "sor", "radius", "ransac"}) append(out, prefixed(OutlierResult::results(method).specs(), method + "."));
  append(out, prefixed(DuplicateResult::results().specs(), "duplicates."));
  append(out, prefixed(SmoothResult::results().specs(), "bilateral."));
  append(out, prefixed(SmoothResult::results(true).specs(), "trilateral."));
  append(out, zero_normals_specs());
  append(out, counted(clean_counts().specs()));
  return out;
}

void run_clean(StageRun& run) {
  DataItem& item = run.context.item(run.output);
  StageRecord& rec = run.record;
  const std::size_t input_points = item.cloud().size();
  std::string steps;
  const double share = 1.0 / double(run.per_method.size());
  for (std::size_t m = 0; m < run.per_method.size(); ++m) {
    const StageArgs& a = run.per_method[m];
    const std::string& name = a.method();
    PointCloud& cloud = item.cloud();
    if (cloud.size() < 4) throw InputError(fmt::format("{} left before {}; cleaning needs at least 4", plural(cloud.size(), "point"), name));
    const ProgressCallback progress = sub_progress(run.progress, share * double(m), share * double(m + 1));
    const bool smoothing = name == "bilateral" || name == "trilateral";
    if (smoothing && !cloud.has_normals()) estimate_missing_normals(run, a.int32("normals_k"), {});
    else if (smoothing) check_input_normals(run, name == "bilateral" ? "not moved" : "not moved, normal kept");
    const KdTree& tree = run.context.tree(run.output);
    const std::size_t before = cloud.size();
    auto removal = [&](const OutlierResult& r) {
      if (r.removed > 0) {
        drop_faces(item, rec);
        cloud = keep_points(cloud, r.kept);
      }
      rec.add(OutlierResult::results(name), r, name + ".");
      steps += fmt::format("{}{} removed {} ({:.2f} %)", steps.empty() ? "" : ", ", name, r.removed, 100.0 * double(r.removed) / double(before));
    };
    auto smoothed = [&](const SmoothResult& r) {
      rec.add(SmoothResult::results(name == "trilateral"), r, name + ".");
      rec.set_used(name + ".radius_used", r.radius_used);
      rec.set_used(name + ".height_sigma_used", r.height_sigma_used);
      steps += fmt::format("{}{} moved {} (rms {:.4g}, max {:.4g})", steps.empty() ? "" : ", ", name, r.moved, r.rms_displacement, r.max_displacement);
    };
    if (name == "local") {
      removal(remove_local_outliers(cloud, local_params(a), &tree, progress));
    } else if (name == "sor") {
      removal(remove_statistical_outliers(cloud, sor_params(a), &tree, progress));
    } else if (name == "radius") {
      const RadiusOutlierParams rp = radius_params(a);
      const OutlierResult r = remove_radius_outliers(cloud, rp, &tree, progress);
      rec.set_used("radius.radius_used", r.threshold);
      if (r.removed == before) {
        // A valid radius that finds no neighbourhood anywhere: the computation failed (exit 3),
        // about --radius, rather than an empty cloud written with exit 0.
        const double spacing = run.context.mean_spacing(run.output);
        ComputeError e(fmt::format("radius: every one of the {} points has fewer than {} others within {:.4g} (mean spacing {:.4g}): all "
                                   "would be removed; use a radius of a few mean spacings (--radius 4sp gives {:.4g}) or a lower "
                                   "--min-neighbors",
                                   before, rp.min_neighbours, r.threshold, spacing, 4.0 * spacing));
        e.set_key("radius");
        throw e;
      }
      removal(r);
    } else if (name == "ransac") {
      const OutlierResult r = remove_ransac_outliers(cloud, ransac_params(a), &tree, progress);
      rec.set_used("ransac.distance_used", r.threshold);
      removal(r);
    } else if (name == "duplicates") {
      const DuplicateParams p = duplicate_params(a);
      const std::size_t faces = item.mesh.triangles.size();
      const DuplicateResult r = find_duplicates(cloud, p, &tree, progress);
      if (r.removed > 0) {
        if (faces > 0) drop_faces(item, rec);
        cloud = merge_duplicates(cloud, r);
      }
      rec.add(DuplicateResult::results(), r, "duplicates.");
      if (!p.exact) rec.set_used("duplicates.distance_used", r.distance_used);
      steps += fmt::format("{}duplicates merged {} ({})", steps.empty() ? "" : ", ", r.removed,
                           p.exact ? "exact" : fmt::format("within {:.4g}", r.distance_used));
    } else if (name == "bilateral") {
      smoothed(smooth_bilateral(cloud, bilateral_params(a), &tree, progress));
    } else {
      smoothed(smooth_trilateral(cloud, trilateral_params(a), &tree, progress));
    }
  }
  rec.add_counts(clean_counts(), CleanCounts{input_points, item.cloud().size()});
  rec.summary = fmt::format("clean: {} -> {}; {}", plural(input_points, "point"), plural(item.cloud().size(), "point"), steps);
}

}  // namespace

StageSpec clean_stage() {
  StageSpec s;
  s.name = "clean";
  s.summary = "Remove outliers and duplicates, denoise (local, sor, radius, ransac, duplicates, bilateral, trilateral)";
  s.description = "The methods of the comma-separated list run in order, each over the previous one's result. The default, "
                  "local, drops points far from the surface relative to the spacing around them, so it keeps the sparse parts "
                  "of a scan; sor is Open3D's statistical removal.";
  s.order = 30;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.methods = {"local", "sor", "radius", "ransac", "duplicates", "bilateral", "trilateral"};
  s.default_method = "local";
  s.method_list = true;
  const std::vector<std::string> smooth = {"bilateral", "trilateral"};
  s.params = params_of(LocalOutlierParams::fields(), {"local"});
  append(s.params, params_of(StatisticalOutlierParams::fields(), {"sor"}));
  append(s.params, params_of(RadiusOutlierParams::fields(), {"radius"}));
  append(s.params, params_of(RansacOutlierParams::fields(), {"ransac"}));
  append(s.params, params_of(DuplicateParams::fields(), {"duplicates"}));
  append(s.params, params_of(BilateralParams::fields(), smooth));
  append(s.params, trilateral_only_params());
  s.params.push_back(P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3).only(smooth));
  s.examples = {"pointsurf clean data/b9_training.ply clean.ply --method sor,duplicates", "pointsurf clean data/kitten.xyz smooth.ply --method trilateral --iterations 3"};
  s.results = clean_specs();
  s.run = run_clean;
  s.check = [](const StageArgs& a) {  // called once per listed method
    if (a.method() == "local") local_params(a).validate();
    else if (a.method() == "sor") sor_params(a).validate();
    else if (a.method() == "radius") radius_params(a).validate();
    else if (a.method() == "ransac") ransac_params(a).validate();
    else if (a.method() == "duplicates") duplicate_params(a).validate();
    else if (a.method() == "bilateral") bilateral_params(a).validate();
    else trilateral_params(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
