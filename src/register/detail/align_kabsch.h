// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The rigid motion that best maps points x_k onto y_k in the least-squares sense (Kabsch 1976;
// Umeyama 1991 without scale): R from the SVD of the cross-covariance, with the reflection
// removed, and t from the centroids. Callers pass coordinates in a local frame (small numbers).
#include <cstddef>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>

namespace pointsurf::detail {

struct RigidFit {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
};

/// The fit from the cross-covariance h = sum (x_k - mean_x) (y_k - mean_y)^T and the centroids.
inline RigidFit fit_rigid(const Eigen::Matrix3d& h, const Eigen::Vector3d& mean_x, const Eigen::Vector3d& mean_y) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0) d(2, 2) = -1.0;
  RigidFit fit;
  fit.rotation = svd.matrixV() * d * svd.matrixU().transpose();
  fit.translation = mean_y - fit.rotation * mean_x;
  return fit;
}

/// `pair(k, x, y)` sets the k-th pair (k < count). Two passes over the pairs (centroids, then
/// the covariance of the centred points), so no precision is lost to a large mean.
template <class Pair>
RigidFit fit_rigid(std::size_t count, Pair&& pair) {
  if (count == 0) return {};
  Eigen::Vector3d x, y, mean_x = Eigen::Vector3d::Zero(), mean_y = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    pair(k, x, y);
    mean_x += x;
    mean_y += y;
  }
  mean_x /= double(count);
  mean_y /= double(count);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    pair(k, x, y);
    h.noalias() += (x - mean_x) * (y - mean_y).transpose();
  }
  return fit_rigid(h, mean_x, mean_y);
}

}  // namespace pointsurf::detail
