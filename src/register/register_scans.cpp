// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/register/multi.h"
#include "register/detail/prepared_scan.h"

namespace pointsurf {

const EnumNames<MultiMode>& multi_mode_names() {
  static const EnumNames<MultiMode> names{{{MultiMode::First, "first"}, {MultiMode::Chain, "chain"}}};
  return names;
}

const char* multi_mode_name(MultiMode mode) noexcept { return multi_mode_names().name(mode).c_str(); }

const FieldTable<RegisterScansParams>& RegisterScansParams::fields() {
  static const FieldTable<RegisterScansParams> table = [] {
    using P = RegisterScansParams;
    FieldTable<P> t;
    t.choice("mode", &P::mode, multi_mode_names(), "Register each scan to the first, or to the one before it");
    t.boolean("refine", &P::refine, "Refine all poses together over every overlapping pair (pose graph)");
    t.number("min_overlap", &P::min_overlap, "Share of a scan within the ICP distance of another for the pair to join the refinement")
        .range(0.0, 1.0, true, false);
    t.nested(&P::pair, RegisterPairParams::fields());
    t.length("prune", &P::prune, "An overlap pair that disagrees with the refined poses by more than this (RMS) is dropped")
        .positive()
        .internal()
        .was("prune_in_spacings");
    t.integer("graph_iterations", &P::graph_iterations, "Gauss-Newton iterations of the pose graph at most").at_least(1).internal();
    return t;
  }();
  return table;
}

void RegisterScansParams::validate() const {
  pair.validate();
  if (!std::isfinite(prune.value)) throw UsageError(fmt::format("register_scans: prune must be finite, got {}", prune.value));
  fields().validate(*this, "register_scans");
}

namespace {

BoundingBox moved_box(const PointCloud& cloud, const RigidTransform& pose) {
  BoundingBox box;
  for (const Vector3d& p : cloud.positions) box.extend(pose.apply(p));
  return box;
}

bool boxes_meet(const BoundingBox& a, const BoundingBox& b, double margin) {
  return (a.min.array() - margin <= b.max.array()).all() && (b.min.array() - margin <= a.max.array()).all();
}

}  // namespace

RegisterScansResult register_scans(const std::vector<PointCloud>& scans, const RegisterScansParams& params, const ProgressCallback& progress) {
  params.validate();
  const std::size_t n = scans.size();
  if (n < 2) throw UsageError(fmt::format("register_scans: {} scan{}; give at least 2", n, n == 1 ? "" : "s"));
  RegisterScansResult out;
  auto t0 = std::chrono::steady_clock::now();

  // Each scan made ready once: normals, trees, spacing; then the common lengths, downsamples
  // and descriptors.
  std::vector<detail::PreparedScan> prepared;
  for (std::size_t i = 0; i < n; ++i) {
    prepared.push_back(detail::prepare_points(scans[i], params.pair, fmt::format("scan {}", i),
                                              detail::progress_part(progress, 0.1 * double(i) / double(n), 0.1 * double(i + 1) / double(n))));
    out.normals_estimated.push_back(prepared.back().normals_estimated ? 1 : 0);
    out.spacing = std::max(out.spacing, prepared.back().spacing);
  }
  const detail::PairLengths lengths = detail::resolve_lengths(params.pair, out.spacing);
  for (std::size_t i = 0; i < n; ++i) {
    detail::prepare_coarse(prepared[i], lengths);
    if (params.pair.global)
      prepared[i].features = compute_descriptors(prepared[i].coarse(), prepared[i].coarse_tree(), lengths.features,
                                                 detail::progress_part(progress, 0.1 + 0.2 * double(i) / double(n), 0.1 + 0.2 * double(i + 1) / double(n)));
  }
  out.seconds_prepare = detail::seconds_since(t0);

  // First pass: every scan placed by one registration.
  t0 = std::chrono::steady_clock::now();
  out.initial_poses.assign(n, RigidTransform());
  for (std::size_t i = 1; i < n; ++i) {
    const std::size_t j = params.mode == MultiMode::First ? 0 : i - 1;
    const RegisterPairResult r = detail::register_prepared(prepared[i], prepared[j], params.pair, lengths,
                                                   detail::progress_part(progress, 0.3 + 0.3 * double(i - 1) / double(n - 1), 0.3 + 0.3 * double(i) / double(n - 1)));
    if (r.result.fitness < params.pair.min_fitness)
      throw ComputeError(fmt::format("scan {} could not be registered to scan {}: {}", i, j, r.result.message));
    out.initial_poses[i] = out.initial_poses[j] * r.result.transform;
    out.links.push_back({i, j, r.result, true, false});
  }
  out.seconds_initial = detail::seconds_since(t0);
  out.poses = out.initial_poses;
  if (!params.refine) return out;

  // Further pairs that overlap under those poses, registered by ICP from there.
  t0 = std::chrono::steady_clock::now();
  const double reach = lengths.fine_icp.max_distance.value;
  std::vector<BoundingBox> boxes;
  for (std::size_t i = 0; i < n; ++i) boxes.push_back(moved_box(prepared[i].coarse(), out.initial_poses[i]));
  RegisterPairParams local = params.pair;
  local.global = false;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      const bool linked = std::any_of(out.links.begin(), out.links.end(), [&](const ScanLink& l) {
        return (l.source == i && l.target == j) || (l.source == j && l.target == i);
      });
      if (linked || !boxes_meet(boxes[i], boxes[j], reach)) continue;
      local.initial = out.initial_poses[j].inverse() * out.initial_poses[i];
      const RegistrationResult overlap =
          evaluate_registration(prepared[i].coarse(), prepared[j].coarse(), prepared[j].coarse_tree(), local.initial, reach);
      if (overlap.fitness < params.min_overlap) continue;
      const RegisterPairResult r = detail::register_prepared(prepared[i], prepared[j], local, lengths, {});
      if (r.result.fitness >= params.pair.min_fitness) out.links.push_back({i, j, r.result, false, false});
    }
    if (progress && !progress(0.6 + 0.3 * double(i + 1) / double(n))) throw CancelledError();
  }
  out.seconds_overlaps = detail::seconds_since(t0);

  // The pose graph over every link, weighted by each link's point pairs on the downsamples.
  t0 = std::chrono::steady_clock::now();
  PoseGraphParams graph;
  graph.max_iterations = params.graph_iterations;
  graph.center = prepared[0].coarse().positions.empty() ? Vector3d::Zero() : bounding_box(prepared[0].coarse().positions).center();
  graph.prune_distance = params.prune.resolve(lengths.spacing);
  std::vector<PoseGraphEdge> edges;
  for (const ScanLink& l : out.links) {
    PoseGraphEdge e;
    e.source = l.source;
    e.target = l.target;
    e.transform = l.result.transform;
    e.information = information_from_pairs(prepared[l.source].coarse(), prepared[l.target].coarse_tree(), l.result.transform,
                                           lengths.fine_icp.max_distance.value, graph.center);
    // Pairs that fit loosely (a thin or grazing overlap, where ICP slides) count for less: the
    // information of a pair is that of a displacement measured with the link's inlier RMSE.
    const double rmse = std::max(l.result.inlier_rmse / lengths.spacing, 1e-3);
    e.information /= rmse * rmse;
    e.uncertain = !l.initial;
    edges.push_back(e);
  }
  out.graph = optimize_pose_graph(out.initial_poses, edges, graph);
  for (std::size_t k : out.graph.pruned) out.links[k].pruned = true;
  out.poses = out.graph.poses;
  out.seconds_graph = detail::seconds_since(t0);
  if (progress && !progress(1.0)) throw CancelledError();
  return out;
}

PointCloud merge_scans(const std::vector<PointCloud>& scans, const std::vector<RigidTransform>& poses) {
  if (scans.size() != poses.size()) throw UsageError(fmt::format("merge_scans: {} scans but {} poses", scans.size(), poses.size()));
  PointCloud merged;
  std::vector<double> scan_of;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    PointCloud moved = scans[i];
    poses[i].apply(moved);
    moved.fields.remove("scan");  // a scan read from a multi-scan file: its own numbering gives way
    merged.append(moved);
    scan_of.insert(scan_of.end(), moved.size(), double(i));
  }
  merged.fields.add("scan", merged.size(), scans.size() <= 65536 ? ScalarType::UInt16 : ScalarType::UInt32).values = std::move(scan_of);
  return merged;
}

const ResultTable<ScanLink>& ScanLink::results() {
  static const ResultTable<ScanLink> table = [] {
    ResultTable<ScanLink> t;
    t.computed("fitness", ResultType::Number, [](const ScanLink& l) { return ResultValue(l.result.fitness); },
               "Fitness of the link from scan * onto scan *")
        .higher_is_better();
    return t;
  }();
  return table;
}

const ResultTable<RegisterScansResult>& RegisterScansResult::results() {
  static const ResultTable<RegisterScansResult> table = [] {
    using R = RegisterScansResult;
    ResultTable<R> t;
    t.number("spacing", &R::spacing, "The largest mean spacing of the scans").with_unit("cloud units");
    t.number("seconds_prepare", &R::seconds_prepare, "Normals, downsamples, descriptors").with_unit("seconds");
    t.number("seconds_initial", &R::seconds_initial, "The first pass").with_unit("seconds");
    t.number("seconds_overlaps", &R::seconds_overlaps, "Finding and registering the other overlapping pairs").with_unit("seconds");
    t.number("seconds_graph", &R::seconds_graph, "The pose graph").with_unit("seconds");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
