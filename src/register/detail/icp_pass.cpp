// SPDX-License-Identifier: GPL-3.0-or-later
#include "register/detail/icp_pass.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "register/detail/align_kabsch.h"

namespace pointsurf::detail {
namespace {

// Points per block of the deterministic reduction: large enough that the per-block sums cost
// nothing, small enough to balance two to a hundred threads.
constexpr std::size_t kBlock = 1024;
// Target points searched for one facing the same way when the nearest does not: enough to cross
// a wall a few spacings thick, and a bound on the work per point.
constexpr std::size_t kCandidates = 32;

}  // namespace

void IcpSums::add(const IcpSums& o) {
  near += o.near;
  near_squared += o.near_squared;
  used += o.used;
  used_squared += o.used_squared;
  sum_p += o.sum_p;
  sum_q += o.sum_q;
  sum_pq += o.sum_pq;
  ata += o.ata;
  atb += o.atb;
}

IcpFrame::IcpFrame(const char* name, const PointCloud& source, const PointCloud& target, const KdTree& target_tree, bool with_normals)
    : target_(target), tree_(target_tree) {
  if (target.empty() || target_tree.size() != target.size())
    throw UsageError(fmt::format("{}: the target kd-tree has {} points, the target {}", name, target_tree.size(), target.size()));
  // The centroid as an offset from one target point, so a far-away cloud sums small numbers.
  const Eigen::Vector3d anchor = target.positions.front();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : target.positions) sum += p - anchor;
  center_ = anchor + sum / static_cast<double>(target.size());
  double squared = 0.0;
  for (const Eigen::Vector3d& p : target.positions) squared += (p - center_).squaredNorm();
  scale_ = std::sqrt(squared / static_cast<double>(target.size()));
  if (!(scale_ > 0.0) || !std::isfinite(scale_)) scale_ = 1.0;

  for (std::size_t i = 0; i < source.size(); ++i)
    if (!source.positions[i].allFinite()) throw InputError(fmt::format("{}: source point {} is not finite", name, i));
  const std::vector<std::uint32_t> order = morton_order(source.positions);
  source_.resize(order.size());
  if (with_normals) normals_.resize(order.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      source_[k] = source.positions[order[k]] - center_;
      if (with_normals) normals_[k] = source.normals[order[k]];
    }
  });
  blocks_.resize((source_.size() + kBlock - 1) / kBlock);
}

IcpSums IcpFrame::pass(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation, double max_distance, double cos_max_normal,
                       IcpSystem system) {
  const double squared_max = max_distance * max_distance;
  const bool check_normals = cos_max_normal > -1.0 && !normals_.empty();
  const double inv_scale = 1.0 / scale_;
  // An undefined (zero) normal on either side says nothing, so such a pair is kept.
  const auto compatible = [cos_max_normal](const Eigen::Vector3d& ns, const Eigen::Vector3d& nt) {
    const double norms = std::sqrt(ns.squaredNorm() * nt.squaredNorm());
    return !(norms > 0.0) || ns.dot(nt) >= cos_max_normal * norms;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks_.size(), 1), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> nn, candidates;
    nn.reserve(1);
    if (check_normals) candidates.reserve(kCandidates);
    for (std::size_t b = r.begin(); b != r.end(); ++b) {
      IcpSums s;
      const std::size_t end = std::min(source_.size(), (b + 1) * kBlock);
      for (std::size_t k = b * kBlock; k < end; ++k) {
        const Eigen::Vector3d p = rotation * source_[k] + translation;
        tree_.hybrid(p + center_, 1, max_distance, nn);
        if (nn.empty() || nn.front().squared_distance > squared_max) continue;
        std::size_t j = nn.front().index;
        double squared = nn.front().squared_distance;
        ++s.near;
        s.near_squared += squared;
        if (check_normals) {
          const Eigen::Vector3d ns = rotation * normals_[k];
          if (!compatible(ns, target_.normals[j])) {
            // The nearest point faces the other way (the far side of a thin wall): take the
            // nearest one that faces the same way, if one is close enough.
            tree_.hybrid(p + center_, kCandidates, max_distance, candidates);
            const auto match = std::find_if(candidates.begin(), candidates.end(),
                                            [&](const Neighbor& c) { return compatible(ns, target_.normals[c.index]); });
            if (match == candidates.end()) continue;
            j = match->index;
            squared = match->squared_distance;
          }
        }
        ++s.used;
        s.used_squared += squared;
        if (system == IcpSystem::None) continue;
        const Eigen::Vector3d q = target_.positions[j] - center_;
        if (system == IcpSystem::PointToPoint) {
          s.sum_p += p;
          s.sum_q += q;
          s.sum_pq.noalias() += p * q.transpose();
        } else {
          const Eigen::Vector3d& n = target_.normals[j];
          Vector6d row;
          row << (inv_scale * p).cross(n), n;
          s.ata.selfadjointView<Eigen::Upper>().rankUpdate(row);
          s.atb -= row * (p - q).dot(n);
        }
      }
      blocks_[b] = s;
    }
  });
  IcpSums total;
  for (const IcpSums& s : blocks_) total.add(s);
  if (system == IcpSystem::PointToPlane) total.ata.triangularView<Eigen::StrictlyLower>() = total.ata.transpose();
  return total;
}

void solve_point_to_point(const IcpSums& sums, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation) {
  const double n = static_cast<double>(sums.used);
  const Eigen::Vector3d mean_p = sums.sum_p / n, mean_q = sums.sum_q / n;
  // Cross-covariance; the frame is centred on the target, so neither term is large against it.
  const RigidFit fit = fit_rigid(Eigen::Matrix3d(sums.sum_pq / n - mean_p * mean_q.transpose()), mean_p, mean_q);
  rotation = fit.rotation;
  translation = fit.translation;
}

void solve_point_to_plane(const IcpSums& sums, double scale, Eigen::Matrix3d& rotation, Eigen::Vector3d& translation) {
  // Minimum-norm solution over the well-determined eigen-directions: a symmetric or flat
  // overlap leaves some directions free, and moving along them would only be noise.
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(sums.ata);
  const Vector6d& lambda = eig.eigenvalues();
  const double floor = 1e-10 * std::max(lambda.maxCoeff(), 0.0);
  Vector6d x = Vector6d::Zero();
  for (int i = 0; i < 6; ++i)
    if (lambda(i) > floor && lambda(i) > 0.0) x += eig.eigenvectors().col(i) * (eig.eigenvectors().col(i).dot(sums.atb) / lambda(i));
  const Eigen::Vector3d omega = x.head<3>() / scale;  // rotation vector, radians
  const double angle = omega.norm();
  rotation = angle > 0.0 ? Eigen::AngleAxisd(angle, omega / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  translation = x.tail<3>();
}

}  // namespace pointsurf::detail
