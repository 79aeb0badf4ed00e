// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/register_pair.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/simplify/simplify.h"
#include "register/detail/prepared_scan.h"

namespace pointsurf {

const FieldTable<RegisterPairParams>& RegisterPairParams::fields() {
  static const FieldTable<RegisterPairParams> table = [] {
    using P = RegisterPairParams;
    FieldTable<P> t;
    // The keys of the nested tables are the stages' own (ransac_iterations, confidence,
    // icp_distance, iterations...): no prefix.
    t.nested(&P::features, DescriptorParams::fields());
    t.length("voxel", &P::voxel, "Cell of the voxel downsample the global alignment and coarse ICP work on (0: every point)")
        .non_negative()
        .was("voxel_in_spacings");
    t.nested(&P::align, AlignParams::fields());
    t.nested(&P::icp, IcpParams::fields());
    t.integer("normals_k", &P::normal_neighbors, "Neighbours for normals when the input has none").at_least(3).unit("points").was("normal_neighbors");
    t.number("min_fitness", &P::min_fitness, "Below this final fitness the clouds are taken as not overlapping (exit 3)").range(0.0, 1.0);
    t.boolean("global_alignment", &P::global,
              "Global alignment from descriptors; false starts ICP from the clouds as they are (already roughly aligned)");
    t.custom<RigidTransform>(
         "initial", &P::initial, ParamType::DoubleList, "Start of ICP when global_alignment is false (4x4 matrix, row by row)",
         [](const RigidTransform& x) {
           const Eigen::Matrix4d m = x.matrix();
           std::vector<double> out;
           for (int r = 0; r < 4; ++r)
             for (int c = 0; c < 4; ++c) out.push_back(m(r, c));
           return ParamValue(out);
         },
         [](RigidTransform& x, const ParamValue& v) {
           const auto& n = std::get<std::vector<double>>(v);
           Eigen::Matrix4d m;
           for (int r = 0; r < 4; ++r)
             for (int c = 0; c < 4; ++c) m(r, c) = n.at(std::size_t(4 * r + c));
           x = RigidTransform::from_matrix(m);
         })
        .internal();
    return t;
  }();
  return table;
}

void RegisterPairParams::validate() const {
  if (!std::isfinite(voxel.value)) throw UsageError(fmt::format("register_pair: voxel must be finite, got {}", voxel.value));
  fields().validate(*this, "register_pair");
  features.validate();
  align.validate();
  icp.validate();
}

namespace detail {

PreparedScan prepare_points(const PointCloud& cloud, const RegisterPairParams& params, const std::string& what, const ProgressCallback& progress) {
  if (cloud.size() < kMinRegistrationPoints)
    throw InputError(fmt::format("{}: {} point{}; registration needs at least {}", what, cloud.size(), cloud.size() == 1 ? "" : "s",
                                 kMinRegistrationPoints));
  PreparedScan s;
  s.cloud = cloud;
  s.tree = std::make_unique<KdTree>(s.cloud.positions);
  s.spacing = mean_spacing(*s.tree);
  if (!(s.spacing > 0.0)) throw InputError(fmt::format("{}: all {} points coincide; nothing to register", what, cloud.size()));
  const bool usable = s.cloud.normals.size() == s.cloud.size() &&
                      std::any_of(s.cloud.normals.begin(), s.cloud.normals.end(), [](const Vector3d& n) { return n.squaredNorm() > 0.0; });
  if (!usable) {
    s.cloud.normals.clear();
    NormalParams np;
    np.k = params.normal_neighbors;
    np.keep_variation = false;
    estimate_normals(s.cloud, np, s.tree.get(), progress_part(progress, 0.0, 0.7));
    orient_normals(s.cloud, OrientParams{}, s.tree.get(), progress_part(progress, 0.7, 1.0));
    s.normals_estimated = true;
  }
  return s;
}

PairLengths resolve_lengths(const RegisterPairParams& params, double largest_spacing) {
  PairLengths l;
  l.spacing = largest_spacing;
  l.voxel = params.voxel.resolve(largest_spacing);
  // A centroid downsample of cell v has points about v apart.
  l.coarse_spacing = l.voxel > 0.0 ? l.voxel : largest_spacing;
  l.features = params.features;
  l.features.radius = Length::cloud(params.features.radius.resolve(l.coarse_spacing));
  l.align = params.align;
  l.align.max_distance = Length::cloud(params.align.max_distance.resolve(l.coarse_spacing));
  l.fine_icp = params.icp;
  l.fine_icp.max_distance = Length::cloud(params.icp.max_distance.resolve(largest_spacing));
  // The coarse ICP starts where RANSAC stopped, within about its inlier distance.
  l.coarse_icp = params.icp;
  l.coarse_icp.max_distance = Length::cloud(std::max(l.align.max_distance.value, l.fine_icp.max_distance.value));
  return l;
}

void prepare_coarse(PreparedScan& scan, const PairLengths& lengths) {
  if (!(lengths.voxel > 0.0)) return;
  GridParams grid;
  grid.target.cell = lengths.voxel;
  PointCloud sampled = simplify_grid(scan.cloud, grid).cloud;
  if (sampled.size() < kMinRegistrationPoints) return;  // a tiny cloud: keep every point
  scan.sampled = std::move(sampled);
  scan.sampled_tree = std::make_unique<KdTree>(scan.sampled->positions);
}

RegisterPairResult register_prepared(const PreparedScan& source, const PreparedScan& target, const RegisterPairParams& params, const PairLengths& lengths,
                             const ProgressCallback& progress) {
  RegisterPairResult out;
  out.spacing = lengths.spacing;
  out.voxel = lengths.voxel;
  out.source_samples = source.coarse().size();
  out.target_samples = target.coarse().size();
  out.source_normals_estimated = source.normals_estimated;
  out.target_normals_estimated = target.normals_estimated;
  RigidTransform start = params.initial;
  auto t0 = std::chrono::steady_clock::now();
  if (params.global) {
    out.global = align_global(source.coarse(), source.features, target.coarse(), target.features, target.coarse_tree(), lengths.align,
                              progress_part(progress, 0.0, 0.6));
    out.seconds_align = seconds_since(t0);
    start = out.global.transform;
  }
  t0 = std::chrono::steady_clock::now();
  out.coarse = icp(source.coarse(), target.coarse(), target.coarse_tree(), start, lengths.coarse_icp, progress_part(progress, 0.6, 0.8));
  out.result = icp(source.cloud, target.cloud, *target.tree, out.coarse.transform, lengths.fine_icp, progress_part(progress, 0.8, 1.0));
  out.seconds_icp = seconds_since(t0);
  if (out.result.fitness < params.min_fitness) {
    out.result.converged = false;
    out.result.message = fmt::format("no overlap found: fitness {:.3g} < min_fitness {:.3g} (pairs within {:.4g} of the target)",
                                     out.result.fitness, params.min_fitness, lengths.fine_icp.max_distance.value);
  }
  return out;
}

}  // namespace detail

RegisterPairResult register_pair(const PointCloud& source, const PointCloud& target, const RegisterPairParams& params, const ProgressCallback& progress) {
  params.validate();
  const auto t0 = std::chrono::steady_clock::now();
  detail::PreparedScan s = detail::prepare_points(source, params, "source", detail::progress_part(progress, 0.0, 0.1));
  detail::PreparedScan t = detail::prepare_points(target, params, "target", detail::progress_part(progress, 0.1, 0.2));
  const detail::PairLengths lengths = detail::resolve_lengths(params, std::max(s.spacing, t.spacing));
  prepare_coarse(s, lengths);
  prepare_coarse(t, lengths);
  const double prepare = detail::seconds_since(t0);
  const auto t1 = std::chrono::steady_clock::now();
  if (params.global) {
    s.features = compute_descriptors(s.coarse(), s.coarse_tree(), lengths.features, detail::progress_part(progress, 0.2, 0.3));
    t.features = compute_descriptors(t.coarse(), t.coarse_tree(), lengths.features, detail::progress_part(progress, 0.3, 0.4));
  }
  const double descriptors = detail::seconds_since(t1);
  RegisterPairResult out = detail::register_prepared(s, t, params, lengths, detail::progress_part(progress, 0.4, 1.0));
  out.seconds_prepare = prepare;
  out.seconds_descriptors = descriptors;
  return out;
}

const ResultTable<RegisterPairResult>& RegisterPairResult::results(bool global) {
  static const std::vector<ResultTable<RegisterPairResult>> tables = [] {
    using R = RegisterPairResult;
    std::vector<ResultTable<R>> out(2);
    for (const bool with_global : {false, true}) {
      ResultTable<R>& t = out[with_global ? 1 : 0];
      t.count("source_samples", &R::source_samples, "Points of the source's downsample").as_count();
      t.count("target_samples", &R::target_samples, "Points of the target's downsample").as_count();
      t.computed("transform", ResultType::Numbers,
                 [](const R& r) {
                   const Eigen::Matrix4d m = r.result.transform.matrix();
                   std::vector<double> rows;
                   for (int i = 0; i < 4; ++i)
                     for (int j = 0; j < 4; ++j) rows.push_back(m(i, j));
                   return ResultValue(std::move(rows));
                 },
                 "4x4 row by row: maps the source onto the target");
      t.computed("rotation_angle_deg", ResultType::Number, [](const R& r) { return ResultValue(r.result.transform.angle_degrees()); },
                 "Rotation angle of the transform")
          .with_unit("degrees");
      t.nested("", &R::result, RegistrationResult::results());
      if (with_global) t.nested("global_", &R::global, RegistrationResult::results());
      t.number("spacing", &R::spacing, "The larger mean spacing of the two clouds").with_unit("cloud units");
      t.number("voxel", &R::voxel, "Cell of the downsample (0: none)").with_unit("cloud units");
      t.number("seconds_prepare", &R::seconds_prepare, "Normals, spacing, downsample, kd-trees").with_unit("seconds");
      t.number("seconds_descriptors", &R::seconds_descriptors, "Descriptors").with_unit("seconds");
      t.number("seconds_align", &R::seconds_align, "Matching and RANSAC").with_unit("seconds");
      t.number("seconds_icp", &R::seconds_icp, "Coarse and fine ICP").with_unit("seconds");
    }
    return out;
  }();
  return tables[global ? 1 : 0];
}

}  // namespace pointsurf
