// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/icp.h"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "register/detail/icp_pass.h"

namespace pointsurf {
namespace {

using detail::IcpFrame;
using detail::IcpSums;
using detail::IcpSystem;

// Standstill: an update smaller than this share of the max distance ends the iterations.
constexpr double kStandstill = 1e-3;

double rmse_of(std::size_t count, double squared) { return count == 0 ? 0.0 : std::sqrt(squared / static_cast<double>(count)); }

// The local (R, t) of the frame centred on `c` that describes the world transform `t`:
// x_local -> R x_local + (t(c) - c).
Eigen::Vector3d local_translation(const RigidTransform& t, const Eigen::Vector3d& c) { return t.apply(c) - c; }

void fill_scores(RegistrationResult& r, const IcpSums& s, std::size_t source_size) {
  r.fitness = source_size == 0 ? 0.0 : static_cast<double>(s.near) / static_cast<double>(source_size);
  r.inlier_rmse = rmse_of(s.near, s.near_squared);
  r.correspondences = s.used;
}

}  // namespace

const EnumNames<IcpMetric>& icp_metric_names() {
  static const EnumNames<IcpMetric> names{{{IcpMetric::PointToPoint, "point"}, {IcpMetric::PointToPlane, "plane"}}};
  return names;
}

const char* icp_metric_name(IcpMetric metric) noexcept { return icp_metric_names().name(metric).c_str(); }

const FieldTable<IcpParams>& IcpParams::fields() {
  static const FieldTable<IcpParams> table = [] {
    using P = IcpParams;
    FieldTable<P> t;
    t.choice("icp", &P::metric, icp_metric_names(), "ICP error: point-to-point or point-to-plane");
    t.length("icp_distance", &P::max_distance, "ICP pairs farther apart than this are rejected (in spacings: of every point)")
        .positive()
        .was("icp_distance_in_spacings");
    t.number("max_normal_angle_deg", &P::max_normal_deg, "ICP pairs whose normals differ more are rejected; 180 disables the check (plain ICP)")
        .unit("degrees")
        .range(0.0, 180.0)
        .was("max_normal_deg");
    t.integer("iterations", &P::max_iterations, "ICP iterations at most (coarse and fine each)").range(1, 100000);
    t.number("relative_fitness", &P::relative_fitness, "Converged when the number of pairs changes by less than this relative amount")
        .non_negative()
        .internal();
    t.number("relative_rmse", &P::relative_rmse, "Converged when the RMSE of the pairs changes by less than this relative amount")
        .non_negative()
        .internal();
    return t;
  }();
  return table;
}

void IcpParams::validate() const {
  if (metric != IcpMetric::PointToPoint && metric != IcpMetric::PointToPlane) throw UsageError("icp: unknown metric");
  if (!std::isfinite(max_distance.value)) throw UsageError(fmt::format("icp: icp_distance must be finite, got {}", max_distance.value));
  if (!std::isfinite(relative_fitness)) throw UsageError(fmt::format("icp: relative_fitness must be finite, got {}", relative_fitness));
  if (!std::isfinite(relative_rmse)) throw UsageError(fmt::format("icp: relative_rmse must be finite, got {}", relative_rmse));
  fields().validate(*this, "icp");
}

RegistrationResult icp(const PointCloud& source, const PointCloud& target, const KdTree& target_tree, const RigidTransform& initial,
                       const IcpParams& params, const ProgressCallback& progress) {
  params.validate();
  const bool plane = params.metric == IcpMetric::PointToPlane;
  const bool check_normals = params.max_normal_deg < 180.0;
  if (plane && !target.has_normals()) throw UsageError("icp: point-to-plane needs the target's normals (estimate them first)");
  if (check_normals && (!source.has_normals() || !target.has_normals()))
    throw UsageError(fmt::format("icp: the normal-angle check (max_normal_angle_deg {}) needs both clouds' normals; estimate them or set "
                                 "max_normal_angle_deg to 180",
                                 params.max_normal_deg));
  source.validate();
  target.validate();

  RegistrationResult result;
  result.transform = initial;
  const std::size_t min_pairs = plane ? 6 : 3;
  if (source.size() < min_pairs) {
    result.message = fmt::format("too few source points ({}; {} needed)", source.size(), min_pairs);
    return result;
  }
  const double max_distance =
      params.max_distance.in_spacings() ? params.max_distance.resolve(mean_spacing(source.positions)) : params.max_distance.value;
  if (!(max_distance > 0.0)) {
    result.message = "the source's points all coincide: no spacing to scale the max distance by";
    return result;
  }

  IcpFrame frame("icp", source, target, target_tree, check_normals);
  const Eigen::Vector3d c = frame.center();
  const double cos_max = check_normals ? std::cos(params.max_normal_deg * std::numbers::pi / 180.0) : -2.0;
  const IcpSystem system = plane ? IcpSystem::PointToPlane : IcpSystem::PointToPoint;

  Eigen::Matrix3d rotation = initial.rotation();
  Eigen::Vector3d translation = local_translation(initial, c);
  IcpSums sums = frame.pass(rotation, translation, max_distance, cos_max, system);
  // An update this small is below what double coordinates of the object's size can express.
  const double tiny_step = 1e-12 * frame.scale();
  // An update that moves the points (RMS, about the centre) by less than this is a standstill:
  // near the optimum ICP often swaps between two pairings, each a few 1e-4 of the max distance
  // from the other, and would go on doing so up to the iteration cap.
  const double standstill = kStandstill * max_distance;
  // The estimate before the current one: back there again after two updates, ICP alternates
  // between two pairings (a couple of pairs in and out at the max distance) and would go on so.
  Eigen::Matrix3d older_rotation = Eigen::Matrix3d::Zero();
  Eigen::Vector3d older_translation = Eigen::Vector3d::Zero();
  for (std::size_t it = 1;; ++it) {
    if (sums.used < min_pairs) {
      result.message = fmt::format("too few pairs ({}; {} needed) within {:.6g}{}", sums.used, min_pairs, max_distance,
                                   check_normals ? fmt::format(" and {} degrees", params.max_normal_deg) : std::string());
      break;
    }
    if (rmse_of(sums.used, sums.used_squared) <= tiny_step) {
      result.converged = true;
      result.message = "the pairs coincide";
      break;
    }
    if (it > params.max_iterations) {
      result.message = fmt::format("stopped at the iteration cap ({}) before the change fell below the thresholds", params.max_iterations);
      break;
    }
    Eigen::Matrix3d step_rotation;
    Eigen::Vector3d step_translation;
    if (plane) detail::solve_point_to_plane(sums, frame.scale(), step_rotation, step_translation);
    else detail::solve_point_to_point(sums, step_rotation, step_translation);
    const Eigen::Matrix3d last_rotation = rotation;
    const Eigen::Vector3d last_translation = translation;
    rotation = RigidTransform::nearest_rotation(step_rotation * rotation);
    translation = step_rotation * translation + step_translation;
    const bool cycle = (rotation - older_rotation).norm() * frame.scale() + (translation - older_translation).norm() <= 0.01 * standstill;
    older_rotation = last_rotation;
    older_translation = last_translation;

    const IcpSums previous = sums;
    sums = frame.pass(rotation, translation, max_distance, cos_max, system);
    result.iterations = it;
    if (progress && !progress(static_cast<double>(it) / static_cast<double>(params.max_iterations))) throw CancelledError("icp: cancelled");

    const double fit_before = static_cast<double>(previous.used), fit_after = static_cast<double>(sums.used);
    const double rmse_before = rmse_of(previous.used, previous.used_squared), rmse_after = rmse_of(sums.used, sums.used_squared);
    const bool small_change = std::abs(fit_after - fit_before) <= params.relative_fitness * fit_before &&
                              std::abs(rmse_after - rmse_before) <= params.relative_rmse * rmse_before + tiny_step;
    const double step_angle = Eigen::AngleAxisd(step_rotation).angle();
    const bool small_step = step_angle * frame.scale() + step_translation.norm() <= standstill;
    if (sums.used >= min_pairs && (small_change || small_step || cycle)) {
      result.converged = true;
      const std::string why = small_change ? std::string()
                              : small_step ? fmt::format(": the update fell below {:.3g}", standstill)
                                           : std::string(": it alternates between two pairings");
      result.message = fmt::format("converged after {} iteration{}{}", it, it == 1 ? "" : "s", why);
      break;
    }
  }
  result.transform = RigidTransform::about(c, rotation, translation);
  fill_scores(result, sums, source.size());
  return result;
}

RegistrationResult evaluate_registration(const PointCloud& source, const PointCloud& target, const KdTree& target_tree,
                                         const RigidTransform& transform, double max_distance) {
  if (!(max_distance > 0.0) || !std::isfinite(max_distance))
    throw UsageError(fmt::format("evaluate_registration: max_distance must be finite and > 0, got {}", max_distance));
  RegistrationResult result;
  result.transform = transform;
  if (source.empty()) {
    result.message = "the source has no points";
    return result;
  }
  IcpFrame frame("evaluate_registration", source, target, target_tree, false);
  const IcpSums sums = frame.pass(transform.rotation(), local_translation(transform, frame.center()), max_distance, -2.0, IcpSystem::None);
  fill_scores(result, sums, source.size());
  result.converged = true;
  result.message = fmt::format("{} of {} source points within {:.6g}", sums.near, source.size(), max_distance);
  return result;
}

}  // namespace pointsurf
