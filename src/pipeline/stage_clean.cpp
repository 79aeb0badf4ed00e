// SPDX-License-Identifier: GPL-3.0-or-later
// The clean stage: outlier removal, duplicates and feature-aware denoising, applied in the
// order of its method list.
#include <cmath>
#include <limits>

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

BilateralParams bilateral_params(const StageArgs& a) {
  BilateralParams p;
  p.radius = a.number("radius");
  p.radius_in_spacings = a.number("radius_in_spacings");
  p.max_neighbours = a.int32("max_neighbours");
  p.height_sigma = a.number("height_sigma");
  p.height_sigma_in_spacings = a.number("height_sigma_in_spacings");
  p.iterations = a.int32("iterations");
  return p;
}

LocalOutlierParams local_params(const StageArgs& a) {
  return {.k = a.int32("k"), .min_ratio = a.number("min_ratio"), .mad_sigmas = a.number("mad_sigmas"), .far_ratio = a.number("far_ratio")};
}

StatisticalOutlierParams sor_params(const StageArgs& a) { return {.k = a.int32("k"), .std_ratio = a.number("std_ratio")}; }

RadiusOutlierParams radius_params(const StageArgs& a) {
  RadiusOutlierParams p;
  p.min_neighbours = a.int32("min_neighbours");
  p.radius = a.number("radius");
  p.radius_in_spacings = a.number("radius_in_spacings");
  return p;
}

RansacOutlierParams ransac_params(const StageArgs& a) {
  RansacOutlierParams p;
  p.k = a.int32("k");
  p.distance = a.number("distance");
  p.distance_in_spacings = a.number("distance_in_spacings");
  p.iterations = a.int32("iterations");
  p.min_support = a.number("min_support");
  p.min_relative_support = a.number("min_relative_support");
  p.seed = static_cast<std::uint64_t>(a.integer("seed"));
  p.primitives = a.boolean("primitives");
  p.primitive_band = a.number("primitive_band");
  return p;
}

DuplicateParams duplicate_params(const StageArgs& a) {
  DuplicateParams p;
  p.exact = a.boolean("exact");
  p.distance = a.number("distance");
  p.distance_in_spacings = a.number("distance_in_spacings");
  return p;
}

TrilateralParams trilateral_params(const StageArgs& a) {
  TrilateralParams p;
  p.position = bilateral_params(a);
  p.sharpness_angle_deg = a.number("sharpness_angle_deg");
  p.normal_iterations = a.int32("normal_iterations");
  p.height_sigma_scale = a.number("height_sigma_scale");
  p.use_feature_field = a.boolean("use_feature_field");
  return p;
}

void run_clean(StageRun& run) {
  DataItem& item = run.context.item(run.output);
  StageRecord& rec = run.record;
  const std::size_t input_points = item.cloud.size();
  std::string steps;
  const double share = 1.0 / double(run.per_method.size());
  for (std::size_t m = 0; m < run.per_method.size(); ++m) {
    const StageArgs& a = run.per_method[m];
    const std::string& name = a.method();
    PointCloud& cloud = item.cloud;
    if (cloud.size() < 4) throw InputError(fmt::format("{} left before {}; cleaning needs at least 4", plural(cloud.size(), "point"), name));
    const ProgressCallback progress = sub_progress(run.progress, share * double(m), share * double(m + 1));
    const bool smoothing = name == "bilateral" || name == "trilateral";
    if (smoothing && !cloud.has_normals()) estimate_missing_normals(run, a.int32("normals_k"), {});
    else if (smoothing) check_input_normals(run, name == "bilateral" ? "not moved" : "not moved, normal kept");
    const KdTree& tree = run.context.tree(run.output);
    const std::size_t before = cloud.size();
    auto removal = [&](const OutlierResult& r, const char* threshold_name) {
      if (r.removed > 0) {
        drop_faces(item, rec);
        cloud = keep_points(cloud, r.kept);
      }
      rec.count(name + ".removed", as_count(r.removed));
      rec.metric(name + "." + threshold_name, r.threshold);
      steps += fmt::format("{}{} removed {} ({:.2f} %)", steps.empty() ? "" : ", ", name, r.removed, 100.0 * double(r.removed) / double(before));
    };
    auto smoothed = [&](const SmoothResult& r) {
      rec.count(name + ".moved", as_count(r.moved));
      rec.metric(name + ".rms_displacement", r.rms_displacement);
      rec.metric(name + ".max_displacement", r.max_displacement);
      rec.set_used(name + ".radius", r.radius_used);
      rec.set_used(name + ".height_sigma", r.height_sigma_used);
      steps += fmt::format("{}{} moved {} (rms {:.4g}, max {:.4g})", steps.empty() ? "" : ", ", name, r.moved, r.rms_displacement, r.max_displacement);
    };
    if (name == "local") {
      removal(remove_local_outliers(cloud, local_params(a), &tree, progress), "ratio_threshold");
    } else if (name == "sor") {
      removal(remove_statistical_outliers(cloud, sor_params(a), &tree, progress),
              "mean_distance_threshold");
    } else if (name == "radius") {
      const OutlierResult r = remove_radius_outliers(cloud, radius_params(a), &tree, progress);
      rec.set_used("radius.radius", r.threshold);
      removal(r, "radius_used");
    } else if (name == "ransac") {
      const OutlierResult r = remove_ransac_outliers(cloud, ransac_params(a), &tree, progress);
      rec.set_used("ransac.distance", r.threshold);
      removal(r, "distance_used");
    } else if (name == "duplicates") {
      const DuplicateParams p = duplicate_params(a);
      const std::size_t faces = item.triangles.size();
      const DuplicateResult r = find_duplicates(cloud, p, &tree, progress);
      if (r.removed > 0) {
        if (faces > 0) drop_faces(item, rec);
        cloud = merge_duplicates(cloud, r);
      }
      rec.count("duplicates.removed", as_count(r.removed));
      rec.metric("duplicates.max_merge_distance", r.max_distance);
      if (!p.exact) rec.set_used("duplicates.distance", r.distance_used);
      steps += fmt::format("{}duplicates merged {} ({})", steps.empty() ? "" : ", ", r.removed,
                           p.exact ? "exact" : fmt::format("within {:.4g}", r.distance_used));
    } else if (name == "bilateral") {
      smoothed(smooth_bilateral(cloud, bilateral_params(a), &tree, progress));
    } else {
      const TrilateralParams p = trilateral_params(a);
      const SmoothResult r = smooth_trilateral(cloud, p, &tree, progress);
      smoothed(r);
      rec.count("trilateral.normals_changed", as_count(r.normals_changed));
      rec.metric("trilateral.mean_normal_change_deg", r.mean_normal_change_deg);
    }
  }
  rec.count("input", as_count(input_points));
  rec.count("output", as_count(item.cloud.size()));
  rec.summary = fmt::format("clean: {} -> {}; {}", plural(input_points, "point"), plural(item.cloud.size(), "point"), steps);
}

}  // namespace

StageSpec clean_stage() {
  const LocalOutlierParams local;
  const StatisticalOutlierParams sor;
  const RadiusOutlierParams radius;
  const RansacOutlierParams ransac;
  const DuplicateParams dup;
  const BilateralParams bil;
  const TrilateralParams tri;
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
  s.params = {
      P::integer("k", local.k, "Neighbours per point, the point excluded").at_least(2).only({"local"}),
      P::number("min_ratio", local.min_ratio, "Drop only points whose mean neighbour distance is above this many times their neighbours'")
          .range(1.0, std::numeric_limits<double>::infinity(), true, false)
          .only({"local"}),
      P::number("mad_sigmas", local.mad_sigmas, "... and above the median ratio by this many robust standard deviations").positive().only({"local"}),
      P::number("far_ratio", local.far_ratio, "Also drop points whose mean neighbour distance is above this many times the cloud's median")
          .range(1.0, std::numeric_limits<double>::infinity(), true, false)
          .only({"local"}),
      P::integer("k", sor.k, "Neighbours per point, the point included").at_least(1).only({"sor"}),
      P::number("std_ratio", sor.std_ratio, "Drop points whose mean kNN distance >= mean + std_ratio x std").positive().only({"sor"}),
      P::integer("min_neighbours", radius.min_neighbours, "Keep points with at least this many others within the radius").at_least(1).only({"radius"}),
      P::number("radius", radius.radius, "Search radius; 0: radius_in_spacings x mean spacing").unit("cloud units").non_negative().meta("R").only(
          {"radius", "bilateral", "trilateral"}),
      P::number("radius_in_spacings", radius.radius_in_spacings, "Radius when radius is 0").unit("mean spacings").positive().only({"radius"}),
      P::integer("k", ransac.k, "Neighbourhood size, the point included").at_least(4).only({"ransac"}),
      P::number("distance", ransac.distance, "Plane distance (ransac) or merge distance (duplicates); 0: distance_in_spacings x mean spacing")
          .unit("cloud units")
          .non_negative()
          .meta("D")
          .only({"ransac", "duplicates"}),
      P::number("distance_in_spacings", ransac.distance_in_spacings, "Plane distance when distance is 0").unit("mean spacings").positive().only({"ransac"}),
      P::integer("iterations", ransac.iterations, "Random planes tried per point").at_least(1).only({"ransac"}),
      P::number("min_support", ransac.min_support, "Fraction of the neighbourhood a plane needs").range(0.0, 1.0, true, false).only({"ransac"}),
      P::number("min_relative_support", ransac.min_relative_support,
                "A plane through the point holding (or scoring) this fraction of the neighbours (of the dominant plane) keeps it")
          .range(0.0, 1.0)
          .only({"ransac"}),
      P::integer("seed", static_cast<std::int64_t>(ransac.seed), "Random seed").at_least(0).only({"ransac"}),
      P::boolean("primitives", ransac.primitives, "Judge points explained by planes, spheres, cylinders, cones (efficient RANSAC) by those")
          .only({"ransac"}),
      P::number("primitive_band", ransac.primitive_band, "A point amid a primitive's inliers farther than this from it is an outlier")
          .unit("plane distances")
          .positive()
          .only({"ransac"}),
      P::boolean("exact", dup.exact, "Merge only points with identical coordinates").only({"duplicates"}),
      P::number("distance_in_spacings", dup.distance_in_spacings, "Merge distance when distance is 0").unit("mean spacings").positive().only({"duplicates"}),
      P::number("radius_in_spacings", bil.radius_in_spacings, "Radius when radius is 0").unit("mean spacings").positive().only(smooth),
      P::integer("max_neighbours", bil.max_neighbours, "At most this many nearest points within the radius").at_least(3).only(smooth),
      P::number("height_sigma", bil.height_sigma, "Range sigma along the normal; 0: height_sigma_in_spacings x mean spacing")
          .unit("cloud units")
          .non_negative()
          .meta("S")
          .only(smooth),
      P::number("height_sigma_in_spacings", bil.height_sigma_in_spacings, "Range sigma when height_sigma is 0").unit("mean spacings").positive().only(smooth),
      P::integer("iterations", bil.iterations, "Position passes").at_least(1).only(smooth),
      P::number("sharpness_angle_deg", tri.sharpness_angle_deg, "Sigma of the angle between normals").unit("degrees").range(0.0, 90.0, true, false).only(
          {"trilateral"}),
      P::integer("normal_iterations", tri.normal_iterations, "Passes of the normal filter").at_least(1).only({"trilateral"}),
      P::number("height_sigma_scale", tri.height_sigma_scale, "Range sigma of the position pass, times the height sigma").positive().only({"trilateral"}),
      P::boolean("use_feature_field", tri.use_feature_field, "Feature points (field \"feature\") do not lend their normals").only({"trilateral"}),
      P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3).only(smooth),
  };
  s.examples = {"pointsurf clean scan.ply clean.ply --method sor,duplicates", "pointsurf clean part.ply smooth.ply --method trilateral --iterations 3"};
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
