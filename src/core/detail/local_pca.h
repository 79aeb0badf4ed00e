// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Principal component analysis of a small point set (a neighbourhood), shared by normals,
// curvature, feature detection and every stage that fits a local plane.
#include <algorithm>
#include <cstddef>

#include <Eigen/Eigenvalues>

namespace pointsurf::detail {

// The middle eigenvalue below this fraction of the largest: a line (or one repeated point),
// no plane and no normal.
inline constexpr double kPcaRankTolerance = 1e-12;
// computeDirect (closed form) loses accuracy in the smallest eigenvector when the two smallest
// eigenvalues cluster; below this gap (relative to the largest) the iterative solver
// recomputes it. That covers near-lines too, whose rank test needs accurate small
// eigenvalues. Rare on real surfaces, where l0 << l1.
inline constexpr double kPcaDirectSolverGap = 1e-4;

struct LocalPca {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();  // centroid, in the offsets' frame
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();    // ascending, of the covariance / m
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Zero();   // columns match eigenvalues
  bool valid = false;  // at least 3 points, solver converged, not a line
  Eigen::Vector3d normal() const { return eigenvectors.col(0).normalized(); }  // unit; sign arbitrary
  // l0 / (l0 + l1 + l2), in [0, 1/3]: 0 on a plane, 1/3 for an isotropic blob.
  double variation() const {
    const double l0 = std::max(eigenvalues[0], 0.0);
    return std::clamp(l0 / (l0 + eigenvalues[1] + eigenvalues[2]), 0.0, 1.0 / 3.0);
  }
};

// PCA of `m` points given by `offset(i)` (offsets from a reference point, so a georeferenced
// cloud is accumulated from small numbers). The covariance is centred on the centroid in a
// second pass (no E[x^2] - E[x]^2 cancellation).
template <class Offset>
LocalPca local_pca(const Offset& offset, std::size_t m) {
  LocalPca out;
  if (m < 3) return out;
  for (std::size_t i = 0; i < m; ++i) out.mean += offset(i);
  out.mean /= double(m);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Vector3d d = offset(i) - out.mean;
    covariance.noalias() += d * d.transpose();
  }
  covariance /= double(m);
  if (!(covariance.trace() > 0.0)) return out;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  Eigen::Vector3d l = solver.eigenvalues();
  if (solver.info() != Eigen::Success || !(l[1] - l[0] > kPcaDirectSolverGap * l[2])) {
    solver.compute(covariance);
    if (solver.info() != Eigen::Success) return out;
    l = solver.eigenvalues();
  }
  if (!(l[1] > kPcaRankTolerance * l[2])) return out;
  out.eigenvalues = l;
  out.eigenvectors = solver.eigenvectors();
  out.valid = out.normal().allFinite();
  return out;
}

}  // namespace pointsurf::detail
