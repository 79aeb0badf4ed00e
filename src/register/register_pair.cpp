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

void PairParams::validate() const {
  if (!(voxel_in_spacings >= 0.0) || !std::isfinite(voxel_in_spacings))
    throw UsageError(fmt::format("voxel_in_spacings must be >= 0, got {}", voxel_in_spacings));
  if (normal_neighbors < 3) throw UsageError(fmt::format("normal_neighbors must be at least 3, got {}", normal_neighbors));
  if (!(min_fitness >= 0.0 && min_fitness <= 1.0)) throw UsageError(fmt::format("min_fitness must be in [0, 1], got {}", min_fitness));
  features.validate();
  align.validate();
  icp.validate();
}

namespace detail {

PreparedScan prepare_points(const PointCloud& cloud, const PairParams& params, const std::string& what, const ProgressCallback& progress) {
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

PairLengths resolve_lengths(const PairParams& params, double largest_spacing) {
  PairLengths l;
  l.spacing = largest_spacing;
  l.voxel = params.voxel_in_spacings * largest_spacing;
  // A centroid downsample of cell v has points about v apart.
  l.coarse_spacing = l.voxel > 0.0 ? l.voxel : largest_spacing;
  l.features = params.features;
  if (l.features.radius <= 0.0) l.features.radius = params.features.radius_in_spacings * l.coarse_spacing;
  l.align = params.align;
  if (l.align.max_distance <= 0.0) l.align.max_distance = params.align.distance_in_spacings * l.coarse_spacing;
  l.fine_icp = params.icp;
  if (l.fine_icp.max_distance <= 0.0) l.fine_icp.max_distance = params.icp.distance_in_spacings * largest_spacing;
  // The coarse ICP starts where RANSAC stopped, within about its inlier distance.
  l.coarse_icp = params.icp;
  l.coarse_icp.max_distance = std::max(l.align.max_distance, l.fine_icp.max_distance);
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

PairResult register_prepared(const PreparedScan& source, const PreparedScan& target, const PairParams& params, const PairLengths& lengths,
                             const ProgressCallback& progress) {
  PairResult out;
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
                                     out.result.fitness, params.min_fitness, lengths.fine_icp.max_distance);
  }
  return out;
}

}  // namespace detail

PairResult register_pair(const PointCloud& source, const PointCloud& target, const PairParams& params, const ProgressCallback& progress) {
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
  PairResult out = detail::register_prepared(s, t, params, lengths, detail::progress_part(progress, 0.4, 1.0));
  out.seconds_prepare = prepare;
  out.seconds_descriptors = descriptors;
  return out;
}

}  // namespace pointsurf
