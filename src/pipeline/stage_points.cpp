// SPDX-License-Identifier: GPL-3.0-or-later
// Stages over the points of one cloud that keep them in place: normals, curvature, features.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/feature_points.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/shape/curvature.h"

namespace pointsurf::detail {
namespace {

const char* orientation_name(Orientation o) { return orientation_names().name(o).c_str(); }

// "neighborhood" given: that kind; not given: radius when only the radius is given, hybrid
// when both k and radius are, else knn.
NeighborhoodKind neighborhood_kind(const StageArgs& a) {
  if (a.given("neighborhood")) {
    const std::string& n = a.text("neighborhood");
    return n == "knn" ? NeighborhoodKind::Knn : n == "radius" ? NeighborhoodKind::Radius : NeighborhoodKind::Hybrid;
  }
  if (a.given("radius")) return a.given("k") ? NeighborhoodKind::Hybrid : NeighborhoodKind::Radius;
  return NeighborhoodKind::Knn;
}

void check_neighborhood(const StageArgs& a) {
  const NeighborhoodKind kind = neighborhood_kind(a);
  if (kind == NeighborhoodKind::Knn && a.given("radius")) throw key_error("radius", "ignored with neighborhood knn (use radius or hybrid)");
  if (kind == NeighborhoodKind::Radius && a.given("k")) throw key_error("k", "ignored with neighborhood radius (use knn or hybrid)");
}

// Below this share of agreement with the input's normals a new orientation is said to
// disagree with them (a few percent of points may sit on thin parts or creases).
constexpr double kInputAgreementWarning = 0.95;

// Points whose normal carries no direction: (0,0,0) from a degenerate neighbourhood, or NaN.
std::size_t zero_normal_count(const PointCloud& cloud) {
  std::size_t zero = 0;
  for (const Vector3d& n : cloud.normals) zero += !(n.allFinite() && n.squaredNorm() > 0.0);
  return zero;
}

// What the normals stage reports besides the library's structs.
struct NormalCounts {
  std::size_t points = 0, zero_normals = 0;
};
const ResultTable<NormalCounts>& point_counts() {
  static const ResultTable<NormalCounts> table = [] {
    ResultTable<NormalCounts> t;
    t.count("points", &NormalCounts::points, "Points");
    return t;
  }();
  return table;
}
const ResultTable<NormalCounts>& zero_normal_counts() {
  static const ResultTable<NormalCounts> table = [] {
    ResultTable<NormalCounts> t;
    t.count("zero_normals", &NormalCounts::zero_normals, "Input normals that are zero or not finite").lower_is_better();
    return t;
  }();
  return table;
}
struct SpacingValue {
  double mean_spacing = 0.0;
};
const ResultTable<SpacingValue>& spacing_metrics() {
  static const ResultTable<SpacingValue> table = [] {
    ResultTable<SpacingValue> t;
    t.number("mean_spacing", &SpacingValue::mean_spacing, "Mean distance to the nearest neighbour").with_unit("cloud units");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> normals_specs() {
  std::vector<ResultSpec> out = counted(point_counts().specs());
  append(out, counted(zero_normal_counts().specs()));
  append(out, NormalResult::results().specs());
  append(out, spacing_metrics().specs());
  append(out, OrientResult::results(Orientation::Mst).specs());
  append(out, NormalAgreement::results().specs());
  return out;
}

// Records how far the estimated normals agree with the ones the input came with.
NormalAgreement record_agreement(const std::vector<Vector3d>& reference, const std::vector<Vector3d>& estimated, StageRecord& rec) {
  const NormalAgreement agreement = compare_normals(reference, estimated);
  if (agreement.compared == 0) return agreement;
  rec.add(NormalAgreement::results(), agreement);
  return agreement;
}

// The library's Params from a stage's arguments: the run and the check before any work build
// them the same way, and the check calls their validate().
NormalParams normal_params(const StageArgs& a) {
  NormalParams params = read_params<NormalParams>(a);
  params.neighborhood = neighborhood_kind(a);
  return params;
}

// "orient" input and keep are the stage's own (the table's parse leaves the method at mst).
OrientParams orient_params(const StageArgs& a) { return read_params<OrientParams>(a); }

CurvatureParams curvature_params(const StageArgs& a) {
  CurvatureParams params = read_params<CurvatureParams>(a);
  params.neighborhood = neighborhood_kind(a);
  return params;
}

FeatureParams feature_params(const StageArgs& a) { return read_params<FeatureParams>(a); }

// The orientation a run uses: "orient" as given; not given, "input" when the input has
// normals (they are the best evidence of each point's side), else the default.
std::string orientation_used(const StageArgs& a, const PointCloud& cloud) {
  if (a.given("orient") || !cloud.has_normals()) return a.text("orient");
  return "input";
}

void run_keep_normals(StageRun& run) {
  PointCloud& cloud = run.context.item(run.output).cloud();
  StageRecord& rec = run.record;
  if (!cloud.has_normals()) throw key_error("orient", " keep: the input has no normals to keep (use mst, viewpoint or direction)");
  const std::size_t zero = zero_normal_count(cloud);
  rec.set_used("orient", std::string("keep"));
  rec.add_counts(point_counts(), NormalCounts{cloud.size(), zero});
  rec.add_counts(zero_normal_counts(), NormalCounts{cloud.size(), zero});
  if (zero == cloud.size()) throw InputError(fmt::format("orient keep: all {} of the input's normals are zero or not finite", cloud.size()));
  if (zero > 0)
    rec.warnings.push_back(fmt::format("{} of the input's normals ({:.2f} %) are zero or not finite, kept as they are", zero,
                                       100.0 * double(zero) / double(cloud.size())));
  rec.summary = fmt::format("normals: {} kept from the input ({} zero)", plural(cloud.size(), "normal"), zero);
}

void run_normals(StageRun& run) {
  const StageArgs& a = run.args;
  DataItem& item = run.context.item(run.output);
  PointCloud& cloud = item.cloud();
  if (cloud.size() < 3) throw InputError(fmt::format("{}; normals need at least 3", plural(cloud.size(), "point")));
  const std::string orientation = orientation_used(a, cloud);
  if (orientation == "keep") return run_keep_normals(run);
  if (orientation == "input" && !cloud.has_normals())
    throw key_error("orient", " input: the input has no normals to agree with (use mst, viewpoint or direction)");
  const NormalParams params = normal_params(a);
  OrientParams orient = orient_params(a);
  if (orientation == "input") orient.method = Orientation::None;  // signs come from the input below

  std::vector<Vector3d> input_normals;
  std::swap(input_normals, cloud.normals);  // estimate from scratch; compare afterwards
  const KdTree& tree = run.context.tree(run.output);
  const double spacing = run.context.mean_spacing(run.output);
  const NormalResult estimated = estimate_normals(cloud, params, &tree, sub_progress(run.progress, 0.0, 0.5));
  StageRecord& rec = run.record;
  rec.set_used("orient", orientation);
  rec.set_used("neighborhood", neighborhood_name(static_cast<int>(params.neighborhood)));
  if (params.neighborhood != NeighborhoodKind::Knn) rec.set_used("radius_used", estimated.radius_used);
  rec.add_counts(point_counts(), NormalCounts{cloud.size(), 0});
  rec.add(NormalResult::results(), estimated);
  rec.add(spacing_metrics(), SpacingValue{spacing});
  const bool by_radius = params.neighborhood != NeighborhoodKind::Knn;
  if (estimated.degenerate == cloud.size()) {
    if (by_radius) {
      // A valid radius that found no neighbourhood: the computation failed (exit 3), about --radius.
      ComputeError e(fmt::format("radius: every one of the {} points has fewer than 3 neighbours within {:.4g} or a degenerate "
                                 "neighbourhood (mean spacing {:.4g}): no normal; use a radius of a few mean spacings "
                                 "(--radius 3sp gives {:.4g}) or --k",
                                 cloud.size(), estimated.radius_used, spacing, 3.0 * spacing));
      e.set_key("radius");
      throw e;
    }
    throw InputError(fmt::format("every one of the {} points has a degenerate neighbourhood (collinear or coincident points): no normal",
                                 cloud.size()));
  }
  if (estimated.degenerate > 0)
    rec.warnings.push_back(fmt::format("{} ({:.2f} %) fewer than 3 neighbours{} or a degenerate neighbourhood: normal (0,0,0), which "
                                       "later stages skip",
                                       estimated.degenerate == 1 ? "1 point has" : fmt::format("{} points have", estimated.degenerate),
                                       100.0 * double(estimated.degenerate) / double(cloud.size()),
                                       by_radius ? fmt::format(" within {:.4g}", estimated.radius_used) : std::string()));
  std::string oriented_text = "not oriented";
  if (orientation == "input") {
    const OrientResult r = orient_to_reference(cloud, input_normals);
    rec.add(OrientResult::results(Orientation::None), r);
    oriented_text = fmt::format("oriented to the input's normals ({} flipped)", r.flipped);
  } else if (orientation == "mst" && !a.given("orient") && !item.scanners.empty() &&
             (item.scanners.size() == 1 || cloud.fields.contains("scan"))) {
    // Scans whose sensor positions are known (E57 poses): each normal faces its own scanner.
    const ScalarField* scan = cloud.fields.find("scan");
    const OrientResult r = orient_to_scanners(cloud, item.scanners, scan ? std::span<const double>(scan->values) : std::span<const double>());
    rec.add(OrientResult::results(Orientation::Viewpoint), r);
    rec.set_used("orient", std::string("scanners"));
    oriented_text = fmt::format("oriented towards the {} ({} flipped)", plural(item.scanners.size(), "scanner position"), r.flipped);
  } else if (orient.method != Orientation::None) {
    const OrientResult r = orient_normals(cloud, orient, &tree, sub_progress(run.progress, 0.5, 1.0));
    rec.add(OrientResult::results(orient.method), r);
    rec.warnings.insert(rec.warnings.end(), r.warnings.begin(), r.warnings.end());
    oriented_text = orient.method == Orientation::Mst ? fmt::format("oriented mst ({}, {} flipped)", plural(r.components, "component"), r.flipped)
                                                      : fmt::format("oriented by {} ({} flipped)", orientation_name(orient.method), r.flipped);
  }
  if (!input_normals.empty()) {
    const NormalAgreement agreement = record_agreement(input_normals, cloud.normals, rec);
    if (orientation != "input" && orient.method != Orientation::None && agreement.share < kInputAgreementWarning)
      rec.warnings.push_back(fmt::format("the new orientation ({}) disagrees with the input's normals on {:.1f} % of {}: "
                                         "--orient input keeps the input's sides, --orient keep its normals",
                                         orientation, 100.0 * (1.0 - agreement.share), plural(agreement.compared, "point")));
  }
  rec.summary = fmt::format("normals: {} ({} {}), {}; mean spacing {:.4g}", plural(cloud.size(), "normal"),
                            params.neighborhood == NeighborhoodKind::Knn ? "k" : params.neighborhood == NeighborhoodKind::Radius ? "radius" : "hybrid",
                            params.neighborhood == NeighborhoodKind::Knn ? std::to_string(params.k) : fmt::format("{:.4g}", estimated.radius_used),
                            oriented_text, spacing);
}

// Normals for stages that need oriented ones when the input has none: PCA over `k`
// neighbours and MST orientation through the context's tree; said in the record.
void estimate_missing_normals_impl(StageRun& run, int k, const ProgressCallback& progress) {
  PointCloud& cloud = run.context.item(run.output).cloud();
  const KdTree& tree = run.context.tree(run.output);
  NormalParams params;
  params.k = k;
  params.keep_variation = false;
  estimate_normals(cloud, params, &tree, sub_progress(progress, 0.0, 0.5));
  const OrientResult oriented = orient_normals(cloud, {}, &tree, sub_progress(progress, 0.5, 1.0));
  run.record.warnings.push_back(fmt::format("no normals in the input; estimated (PCA, k = {}) and MST-oriented", k));
  run.record.warnings.insert(run.record.warnings.end(), oriented.warnings.begin(), oriented.warnings.end());
}

// What curvature reports besides CurvatureScale and CurvatureResult.
struct CurvatureValues {
  double median_residual = 0.0;
  bool normals_estimated = false;
};
const ResultTable<CurvatureValues>& curvature_metrics() {
  static const ResultTable<CurvatureValues> table = [] {
    ResultTable<CurvatureValues> t;
    t.number("median_residual", &CurvatureValues::median_residual, "Median RMS residual of the jet fits").with_unit("cloud units");
    t.flag("normals_estimated", &CurvatureValues::normals_estimated, "The input had no normals: they were estimated");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> curvature_specs() {
  std::vector<ResultSpec> out = CurvatureScale::results().specs();
  append(out, counted(zero_normal_counts().specs()));
  append(out, counted(point_counts().specs()));
  append(out, CurvatureResult::results().specs());
  append(out, curvature_metrics().specs());
  return out;
}

void run_curvature(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud();
  CurvatureParams params = curvature_params(a);
  const std::size_t needed = params.degree == 2 ? 6 : 10;
  if (cloud.size() < needed) throw InputError(fmt::format("{}; a degree-{} jet needs at least {}", plural(cloud.size(), "point"), params.degree, needed));
  // The scale comes first: normals estimated here need it too, or on noisy input their signs
  // (hence the curvature's) are as noisy as their directions.
  std::optional<CurvatureScale> scale;
  if (params.k == 0 && params.neighborhood == NeighborhoodKind::Knn) {
    scale = choose_curvature_scale(cloud, params, run.context.tree(run.output));
    params.k = scale->k;
    params.cylinder = scale->cylinder;
  }
  const bool estimated = !cloud.has_normals();
  if (estimated) estimate_missing_normals_impl(run, std::max(a.int32("normals_k"), scale ? scale->k : 0), sub_progress(run.progress, 0.0, 0.3));
  else check_input_normals(run, "curvature 0, surface_type 0 (undefined)");
  const KdTree& tree = run.context.tree(run.output);
  const CurvatureResult r = estimate_curvature(cloud, params, &tree, sub_progress(run.progress, estimated ? 0.3 : 0.0, 1.0));
  StageRecord& rec = run.record;
  if (scale) {
    rec.add(CurvatureScale::results(), *scale);
    if (scale->capped)
      rec.warnings.push_back(fmt::format("the noise ({:.3g}) needs a neighbourhood radius of {:.3g} ({} times it), but k stopped at {} "
                                         "(radius {:.3g}; max_k {}, {}): the curvature may be noise-dominated (check the share "
                                         "of flat points); raise max_k or smooth the points first",
                                         scale->noise, params.scale_in_noise * scale->noise, params.scale_in_noise, scale->k,
                                         scale->radius, params.max_k, plural(cloud.size(), "point")));
  }
  rec.set_used("neighborhood", neighborhood_name(static_cast<int>(params.neighborhood)));
  if (params.neighborhood != NeighborhoodKind::Radius) rec.set_used("k", std::int64_t{r.k_used});
  if (params.neighborhood != NeighborhoodKind::Knn) rec.set_used("radius_used", r.radius_used);
  rec.set_used("zero_curvature", r.zero_curvature);
  rec.add_counts(point_counts(), NormalCounts{cloud.size(), 0});
  rec.add(CurvatureResult::results(), r);
  rec.add(curvature_metrics(), CurvatureValues{r.median_residual, estimated});
  if (r.degenerate > 0)
    rec.warnings.push_back(fmt::format("{} a zero normal, too few neighbours or a singular jet fit: curvature 0, surface_type 0 (undefined)",
                                       r.degenerate == 1 ? "1 point has" : fmt::format("{} points have", r.degenerate)));
  std::size_t best = 1;
  for (std::size_t t = 2; t < r.type_counts.size(); ++t)
    if (r.type_counts[t] > r.type_counts[best]) best = t;
  rec.summary = fmt::format("curvature: {} (degree {}, {}{}), zero at {:.3g}, mostly {} ({:.1f} %), {} degenerate",
                            plural(cloud.size(), "point"), params.degree,
                            params.neighborhood == NeighborhoodKind::Radius ? fmt::format("radius {:.4g}", r.radius_used) : fmt::format("k {}", r.k_used),
                            estimated ? ", normals estimated" : "", r.zero_curvature, surface_type_name(static_cast<SurfaceType>(best)),
                            100.0 * double(r.type_counts[best]) / double(std::max<std::size_t>(cloud.size(), 1)), r.degenerate);
}

// What features reports besides FeatureResult: the score against truth_field, when given.
struct FeatureScore {
  std::size_t truth_points = 0;
  double precision = 0.0, recall = 0.0;
};
const ResultTable<FeatureScore>& score_counts() {
  static const ResultTable<FeatureScore> table = [] {
    ResultTable<FeatureScore> t;
    t.count("truth_points", &FeatureScore::truth_points, "Points marked in truth_field");
    return t;
  }();
  return table;
}
const ResultTable<FeatureScore>& score_metrics() {
  static const ResultTable<FeatureScore> table = [] {
    ResultTable<FeatureScore> t;
    t.number("precision", &FeatureScore::precision, "Share of labelled points that truth_field marks").higher_is_better();
    t.number("recall", &FeatureScore::recall, "Share of marked points that are labelled").higher_is_better();
    return t;
  }();
  return table;
}
std::vector<ResultSpec> features_specs() {
  std::vector<ResultSpec> out = counted(zero_normal_counts().specs());
  append(out, counted(point_counts().specs()));
  append(out, FeatureResult::results().specs());
  append(out, counted(score_counts().specs()));
  append(out, score_metrics().specs());
  return out;
}

void run_features(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud();
  const FeatureParams params = feature_params(a);
  if (cloud.size() < static_cast<std::size_t>(params.k) + 1)
    throw InputError(fmt::format("{}; feature detection with k = {} needs at least {}", plural(cloud.size(), "point"), params.k, params.k + 1));
  const std::string& truth_name = a.text("truth_field");
  if (!truth_name.empty() && !cloud.fields.contains(truth_name))
    throw key_error("truth_field", fmt::format("the input has no field \"{}\"", truth_name));
  bool estimated = false;
  if (params.normals == FeatureNormals::Input && !cloud.has_normals()) {
    estimate_missing_normals_impl(run, params.k, sub_progress(run.progress, 0.0, 0.3));
    estimated = true;
  } else if (params.normals == FeatureNormals::Input) {
    check_input_normals(run, "left out of the normal clusters");
  }
  const KdTree& tree = run.context.tree(run.output);
  const FeatureResult r = detect_feature_points(cloud, params, &tree, sub_progress(run.progress, estimated ? 0.3 : 0.0, 1.0));
  StageRecord& rec = run.record;
  rec.set_used("variation_threshold", r.variation_threshold_used);
  rec.set_used("plane_distance_used", r.dd_used);
  rec.add_counts(point_counts(), NormalCounts{cloud.size(), 0});
  rec.add(FeatureResult::results(), r);
  std::string scored;
  if (!truth_name.empty()) {
    const std::vector<double>& truth = cloud.fields.find(truth_name)->values;
    const std::vector<double>& labels = cloud.fields.find("feature")->values;
    std::size_t labelled = 0, expected = 0, both = 0;
    for (std::size_t i = 0; i < labels.size(); ++i) {
      const bool l = labels[i] != 0.0, t = truth[i] != 0.0;
      labelled += l;
      expected += t;
      both += l && t;
    }
    const double precision = labelled == 0 ? 0.0 : double(both) / double(labelled);
    const double recall = expected == 0 ? 0.0 : double(both) / double(expected);
    rec.add_counts(score_counts(), FeatureScore{expected, precision, recall});
    rec.add(score_metrics(), FeatureScore{expected, precision, recall});
    scored = fmt::format(", precision {:.3f} recall {:.3f} against '{}'", precision, recall, truth_name);
  }
  rec.summary = fmt::format("features: {}, {}, {} edge and {} corner {} (threshold {:.4g}, dd {:.4g}){}", plural(cloud.size(), "point"),
                            plural(r.candidates, "candidate"), r.edges, r.corners, r.edges + r.corners == 1 ? "point" : "points",
                            r.variation_threshold_used,
                            r.dd_used, scored);
}

}  // namespace

void estimate_missing_normals(StageRun& run, int k, const ProgressCallback& progress) { estimate_missing_normals_impl(run, k, progress); }

std::size_t check_input_normals(StageRun& run, const std::string& skipped) {
  const PointCloud& cloud = run.context.item(run.output).cloud();
  const std::size_t zero = zero_normal_count(cloud);
  if (zero == 0) return 0;
  if (zero == cloud.size())
    throw InputError(fmt::format("all {} normals of the input are (0,0,0) or not finite; estimate them again with more "
                                 "neighbours (normals --k, or a --radius of a few mean spacings)",
                                 cloud.size()));
  run.record.add_counts(zero_normal_counts(), NormalCounts{cloud.size(), zero});
  run.record.warnings.push_back(fmt::format("{} ({:.2f} %) a zero or non-finite normal in the input: {}", zero == 1 ? "1 point has" : fmt::format("{} points have", zero),
                                            100.0 * double(zero) / double(cloud.size()), skipped));
  return zero;
}

std::vector<ResultSpec> zero_normals_specs() { return counted(zero_normal_counts().specs()); }

StageSpec normals_stage() {
  StageSpec s;
  s.name = "normals";
  s.summary = "Estimate normals by PCA and orient them (MST propagation by default)";
  s.description = "PCA normals (Hoppe et al. 1992) over k nearest neighbours, a radius or both, then a consistent orientation. "
                  "Adds the field \"variation\". When the input has normals, each new one takes the side of the input's unless "
                  "orient is given; another orientation that disagrees with them on more than 5 % of points is warned of. "
                  "A mesh keeps its faces.";
  s.order = 50;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = params_of(NormalParams::fields());
  append(s.params, params_of(OrientParams::fields()));
  // "input" and "keep" are the stage's own: they need the normals the input came with.
  for (ParamSpec& p : s.params)
    if (p.name == "orient") {
      p.choices.insert(p.choices.end(), {"input", "keep"});
      p.meta += "|input|keep";
      p.doc = "Orientation: mst (consistent, Hoppe 1992), viewpoint, direction, none, input (each new normal on the side of the "
              "input's) or keep (the input's normals, no estimation); default: input when the input has normals, else mst";
    }
  s.examples = {"pointsurf normals data/kitten.xyz oriented.ply --k 30 --orient mst",
                "pointsurf normals data/b9_training.ply b9_oriented.ply --orient viewpoint --viewpoint 596693,243676,300"};
  s.results = normals_specs();
  s.run = run_normals;
  s.check = [](const StageArgs& a) {
    check_neighborhood(a);
    const std::string& orient = a.text("orient");
    if (a.given("viewpoint") && orient != "viewpoint") throw key_error("viewpoint", "ignored unless orient is viewpoint");
    if (a.given("direction") && orient != "direction") throw key_error("direction", "ignored unless orient is direction");
    if (a.given("orient_k") && orient != "mst") throw key_error("orient_k", "ignored unless orient is mst");
    if (orient == "keep")
      for (const char* name : {"neighborhood", "k", "radius"})
        if (a.given(name)) throw UsageError(fmt::format("{}: ignored with orient keep (no estimation)", name));
    if (orient == "viewpoint" && !a.given("viewpoint")) throw key_error("orient", " viewpoint needs viewpoint X,Y,Z (the scanner position)");
    normal_params(a).validate();
    orient_params(a).validate();
  };
  return s;
}

StageSpec curvature_stage() {
  StageSpec s;
  s.name = "curvature";
  s.summary = "Principal curvatures, mean and Gaussian curvature, variation and HK surface type by jet fitting";
  s.description = "Fields k1 >= k2, mean, gauss, variation, surface_type (Cazals and Pouget 2005). Normals are estimated and "
                  "MST-oriented when the input has none.";
  s.order = 60;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = params_of(CurvatureParams::fields());
  s.params.push_back(P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3));
  s.examples = {"pointsurf curvature data/kitten.xyz kitten_curvature.ply --degree 3"};
  s.results = curvature_specs();
  s.run = run_curvature;
  s.check = [](const StageArgs& a) {
    check_neighborhood(a);
    const int min_k = a.integer("degree") == 2 ? 6 : 10;
    if (a.integer("k") != 0 && a.integer("k") < min_k)
      throw key_error("k", fmt::format("{} must be at least {} for degree {} (or 0: the default)", a.integer("k"), min_k, a.integer("degree")));
    curvature_params(a).validate();
  };
  return s;
}

StageSpec features_stage() {
  StageSpec s;
  s.name = "features";
  s.summary = "Sharp-feature points: field \"feature\" = 0 none, 1 edge, 2 corner";
  s.description = "Candidates by surface variation, then clusters of neighbour normals give planes; a point on two planes is an "
                  "edge, on three or more a corner.";
  s.order = 70;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = params_of(FeatureParams::fields());
  s.params.push_back(P::text("truth_field", "", "Field marking true feature points (non-zero): report precision and recall").meta("NAME"));
  s.examples = {"pointsurf features data/b9_training.ply b9_features.ply --report features.json"};
  s.results = features_specs();
  s.run = run_features;
  s.check = [](const StageArgs& a) {
    if (a.integer("min_cluster_points") > a.integer("k"))
      throw key_error("min_cluster_points", fmt::format("{} must be at most k = {}", a.integer("min_cluster_points"), a.integer("k")));
    feature_params(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
