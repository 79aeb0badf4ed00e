// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What every registration step answers: the transform mapping the source onto the target and
// how well it fits. A registration that does not converge is an answer (converged = false, with
// the reason in `message`), never an exception.
#include <cstddef>
#include <string>

#include "pointsurf/core/rigid_transform.h"
#include "pointsurf/core/results.h"

namespace pointsurf {

struct RegistrationResult {
  RigidTransform transform;          // maps source points onto the target
  double fitness = 0.0;              // share of source points with a target point within the
                                     // step's max distance after the transform, in [0, 1]
  double inlier_rmse = 0.0;          // RMS distance of those pairs, cloud units
  std::size_t correspondences = 0;   // pairs (ICP) or inlier matches (RANSAC) behind the answer
  std::size_t iterations = 0;        // ICP iterations or RANSAC trials run
  bool converged = false;            // ICP: a stop criterion met; RANSAC: the confidence reached
                                     // or a model with enough inliers found
  std::string message;               // why it stopped (one line)

  /// The reported members of a registration of a source onto a target (core/results.h): how
  /// well it fits (the transform is its caller's to report).
  static const ResultTable<RegistrationResult>& results();
};

}  // namespace pointsurf
