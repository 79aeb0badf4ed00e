// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A fixed order of positions (x, then y, then z), for results that must not depend on the
// input order and for finding exact copies by sorting.
#include <Eigen/Core>

namespace pointsurf::detail {

inline bool lexicographic_less(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.z() < b.z();
}

}  // namespace pointsurf::detail
