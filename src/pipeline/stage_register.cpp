// SPDX-License-Identifier: GPL-3.0-or-later
// The registration stages: `register` (a source cloud onto a target; pointsurf/register/
// register_pair.h) and `register-many` (several scans into the first one's frame, merged;
// pointsurf/register/multi.h).
#include <Eigen/Core>

#include <filesystem>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/transform_file.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/register/multi.h"

namespace pointsurf::detail {
namespace {

std::vector<double> matrix_list(const RigidTransform& t) {
  const Eigen::Matrix4d m = t.matrix();
  std::vector<double> out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out.push_back(m(r, c));
  return out;
}

RegisterPairParams pair_params(const StageArgs& a) { return read_params<RegisterPairParams>(a); }

// What register reports besides RegisterPairResult: the sizes of the two clouds.
struct PairInputs {
  std::size_t source_points = 0, target_points = 0;
};
const ResultTable<PairInputs>& input_counts() {
  static const ResultTable<PairInputs> table = [] {
    ResultTable<PairInputs> t;
    t.count("source_points", &PairInputs::source_points, "Points of the source");
    t.count("target_points", &PairInputs::target_points, "Points of the target");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> register_specs() {
  std::vector<ResultSpec> out = counted(input_counts().specs());
  append(out, RegisterPairResult::results(true).specs());
  return out;
}

void run_register(StageRun& run) {
  const RegisterPairParams params = pair_params(run.args);
  const DataItem& source = run.context.item(run.inputs[0]);
  const PointCloud& target = run.context.item(run.inputs[1]).cloud();
  const RegisterPairResult r = register_pair(source.cloud(), target, params, run.progress);
  StageRecord& rec = run.record;
  rec.add_counts(input_counts(), PairInputs{source.cloud().size(), target.size()});
  rec.add(RegisterPairResult::results(params.global), r);
  for (const auto& [estimated, name] : {std::pair{r.source_normals_estimated, "source"}, std::pair{r.target_normals_estimated, "target"}})
    if (estimated)
      rec.warnings.push_back(fmt::format("the {} has no normals; estimated (PCA, k = {}) and MST-oriented", name, params.normal_neighbors));
  if (r.result.fitness < params.min_fitness)
    throw ComputeError(fmt::format("{}; check that the clouds overlap, or lower min_fitness", r.result.message));
  if (!r.result.converged) rec.warnings.push_back(fmt::format("ICP did not converge: {}", r.result.message));
  rec.summary = fmt::format("register: {} onto {}: rotation {:.3g} degrees, translation {:.4g}, fitness {:.3f}, inlier RMSE {:.3g}",
                            run.inputs[0], run.inputs[1], r.result.transform.angle_degrees(), r.result.transform.translation().norm(),
                            r.result.fitness, r.result.inlier_rmse);

  DataItem moved = source;  // a mesh keeps its faces: the motion is rigid
  r.result.transform.apply(moved.cloud());
  run.context.set(run.output, std::move(moved));

  const std::string& out = run.args.text("out");
  if (!out.empty()) {
    TransformFile file;
    file.transform = r.result.transform;
    const double total = r.seconds_prepare + r.seconds_descriptors + r.seconds_align + r.seconds_icp;
    file.members = {{"fitness", r.result.fitness},
                    {"inlier_rmse", r.result.inlier_rmse},
                    {"iterations", std::int64_t(r.result.iterations)},
                    {"converged", r.result.converged},
                    {"descriptor", std::string(params.global ? descriptor_type_name(params.features.type) : "none")},
                    {"icp", std::string(icp_metric_name(params.icp.metric))},
                    {"global_fitness", r.global.fitness},
                    {"spacing", r.spacing},
                    {"seconds", std::vector<double>{r.seconds_prepare, r.seconds_descriptors, r.seconds_align, r.seconds_icp, total}},
                    {"seconds_steps", std::string("prepare, descriptors, align, icp, total")}};
    write_transform_file(out, file);
  }
}

RegisterScansParams multi_params(const StageArgs& a) { return read_params<RegisterScansParams>(a); }

// What register-many reports: per scan (under "points_<tag>" and "pose_<i>"), each ScanLink
// (under "link_<source>_<target>_"), then the links counted, PoseGraphResult (under "graph_")
// and RegisterScansResult.
struct ScanPoints {
  std::size_t points = 0;
};
const ResultTable<ScanPoints>& scan_points_counts() {
  static const ResultTable<ScanPoints> table = [] {
    ResultTable<ScanPoints> t;
    t.count("", &ScanPoints::points, "Points of the scan whose tag is *");
    return t;
  }();
  return table;
}
const ResultTable<RigidTransform>& pose_metrics() {
  static const ResultTable<RigidTransform> table = [] {
    ResultTable<RigidTransform> t;
    t.computed("", ResultType::Numbers, [](const RigidTransform& p) { return ResultValue(matrix_list(p)); },
               "Pose of scan * (4x4 row by row): maps it into scan 0's frame");
    return t;
  }();
  return table;
}
struct Links {
  std::size_t links = 0, overlap_links = 0, pruned_links = 0, points = 0;
};
const ResultTable<Links>& link_counts() {
  static const ResultTable<Links> table = [] {
    ResultTable<Links> t;
    t.count("links", &Links::links, "Pairwise registrations");
    t.count("overlap_links", &Links::overlap_links, "Of those, the ones found by overlap (after the first pass)");
    t.count("pruned_links", &Links::pruned_links, "Links the pose graph dropped");
    return t;
  }();
  return table;
}
const ResultTable<Links>& merged_counts() {
  static const ResultTable<Links> table = [] {
    ResultTable<Links> t;
    t.count("points", &Links::points, "Points of the merged cloud");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> register_many_specs() {
  std::vector<ResultSpec> out = counted(scan_points_counts().specs(), "points_*");
  append(out, prefixed(pose_metrics().specs(), "pose_*"));
  append(out, prefixed(ScanLink::results().specs(), "link_*_*_"));
  append(out, counted(link_counts().specs()));
  append(out, prefixed(PoseGraphResult::results().specs(), "graph_"));
  append(out, RegisterScansResult::results().specs());
  append(out, counted(merged_counts().specs()));
  return out;
}

void run_register_many(StageRun& run) {
  const RegisterScansParams params = multi_params(run.args);
  std::vector<PointCloud> scans;
  std::size_t faces = 0;
  for (const std::string& tag : run.inputs) {
    const DataItem& item = run.context.item(tag);
    faces += item.mesh.triangles.size();
    scans.push_back(item.cloud());
  }
  const RegisterScansResult r = register_scans(scans, params, run.progress);
  StageRecord& rec = run.record;
  if (faces > 0) rec.warnings.push_back(fmt::format("register-many works on points: {} dropped", plural(faces, "face")));
  for (std::size_t i = 0; i < scans.size(); ++i) {
    if (r.normals_estimated[i])
      rec.warnings.push_back(fmt::format("scan {} ({}) has no normals; estimated (PCA, k = {}) and MST-oriented", i, run.inputs[i],
                                         params.pair.normal_neighbors));
    rec.add_counts(scan_points_counts(), ScanPoints{scans[i].size()}, "points_" + run.inputs[i]);
    rec.add(pose_metrics(), r.poses[i], fmt::format("pose_{}", i));
  }
  std::size_t initial = 0, pruned = 0;
  for (const ScanLink& l : r.links) {
    initial += l.initial;
    pruned += l.pruned;
    rec.add(ScanLink::results(), l, fmt::format("link_{}_{}_", l.source, l.target));
    if (!l.result.converged) rec.warnings.push_back(fmt::format("ICP of scan {} onto scan {} did not converge: {}", l.source, l.target, l.result.message));
  }
  Links links{r.links.size(), r.links.size() - initial, pruned, 0};
  rec.add_counts(link_counts(), links);
  if (params.refine) rec.add(PoseGraphResult::results(), r.graph, "graph_");
  rec.add(RegisterScansResult::results(), r);
  PointCloud merged = merge_scans(scans, r.poses);
  links.points = merged.size();
  rec.add_counts(merged_counts(), links);
  // One T.json per scan on request: its pose, mapping it into the first scan's frame, as
  // `register --out` writes one and `transform --file` reads it.
  if (const std::string& dir = run.args.text("poses"); !dir.empty()) {
    std::filesystem::create_directories(dir);
    for (std::size_t i = 0; i < scans.size(); ++i) {
      const std::string& source = run.context.item(run.inputs[i]).source;
      const std::string stem = source.empty() ? run.inputs[i] : std::filesystem::path(source).stem().string();
      TransformFile file;
      file.transform = r.poses[i];
      file.members = {{"scan", std::int64_t(i)}, {"input", source.empty() ? run.inputs[i] : source},
                      {"frame", std::string("the first scan's: ") + (run.context.item(run.inputs[0]).source.empty() ? run.inputs[0]
                                                                                                                   : run.context.item(run.inputs[0]).source)},
                      {"refined", params.refine}};
      const std::filesystem::path path = std::filesystem::path(dir) / fmt::format("scan_{}_{}.json", i, stem);
      write_transform_file(path, file);
    }
  }
  rec.summary = fmt::format("register-many: {} in one frame ({} of them, {} links, {} pruned), {}{}", plural(scans.size(), "scan"),
                            multi_mode_name(params.mode), r.links.size(), pruned, plural(merged.size(), "point"),
                            run.args.text("poses").empty() ? "" : "; poses written to " + run.args.text("poses"));
  run.context.set_cloud(run.output, std::move(merged), run.inputs.front());
}

}  // namespace

StageSpec register_stage() {
  StageSpec s;
  s.name = "register";
  s.shape = CommandShape::Pair;
  s.summary = "Register a source cloud onto a target (descriptors, RANSAC, ICP): the moved source and T.json";
  s.description =
      "Finds the rigid transform taking SOURCE onto TARGET from their points alone: PFH or FPFH descriptors of a voxel downsample, "
      "RANSAC over mutual descriptor matches, then ICP rejecting pairs by distance and by normal angle, first on the downsample and "
      "then on every point. Every length defaults to a multiple of the mean spacing (\"3sp\"; a plain number is in cloud units). Missing normals are estimated (with a warning). Writes "
      "the transform as T.json (--out: \"matrix\" 4x4 row by row, fitness, inlier_rmse, iterations, converged, timings) and the "
      "moved source (--apply). Clouds that do not overlap end with exit code 3.";
  s.order = 75;
  s.consumes = {Slot{"source", DataKind::Any}, Slot{"target", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = params_of(RegisterPairParams::fields());
  s.params.push_back(P::text("out", "", "Write the transform as a T.json file (empty: none; the record holds it too)").meta("T.json"));
  s.writes_param = "out";
  s.examples = {"pointsurf transform data/kitten.xyz moved.ply --matrix 0.8660254037844387,-0.5,0,0.05,0.5,0.8660254037844387,0,0.02,0,0,1,-0.03,0,0,0,1",
                "pointsurf register moved.ply data/kitten.xyz --out T.json",
                "pointsurf register moved.ply data/kitten.xyz --out T.json --apply back.ply --descriptor pfh --icp point",
                "pointsurf transform moved.ply back2.ply --file T.json"};
  s.results = register_specs();
  s.run = run_register;
  s.check = [](const StageArgs& a) { pair_params(a).validate(); };
  return s;
}

StageSpec register_many_stage() {
  StageSpec s;
  s.name = "register-many";
  s.shape = CommandShape::Merge;
  s.summary = "Register several scans into the first one's frame and merge them (field scan)";
  s.description =
      "Registers each scan to the first (--mode first) or to the one before it (--mode chain) as `register` does, then registers "
      "every further pair that overlaps under those poses and refines all poses together on a pose graph (least squares, the first "
      "scan fixed; wrong loop closures dropped). The merged cloud holds a field \"scan\" (0 for the first input); the poses are in "
      "the report, and with --poses DIR one T.json per scan (DIR/scan_<i>_<name>.json, readable by transform --file).";
  s.order = 76;
  s.consumes = {Slot{"clouds", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.params = params_of(RegisterScansParams::fields());
  s.params.push_back(
      P::text("poses", "", "Write each scan's pose as a T.json file in this directory, scan_<i>_<name>.json (empty: none)").meta("DIR"));
  s.examples = {"pointsurf transform data/kitten.xyz moved.ply --matrix 0.8660254037844387,-0.5,0,0.05,0.5,0.8660254037844387,0,0.02,0,0,1,-0.03,0,0,0,1",
                "pointsurf register-many data/kitten.xyz moved.ply --out merged.ply",
                "pointsurf register-many data/kitten.xyz moved.ply merged_first.ply --mode first --icp point"};
  s.results = register_many_specs();
  s.run = run_register_many;
  s.check = [](const StageArgs& a) { multi_params(a).validate(); };
  return s;
}

}  // namespace pointsurf::detail
