// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A polyline in 3D: an outline, a section, a boundary loop.
#include <vector>

#include <Eigen/Core>

namespace pointsurf {

struct Polyline {
  std::vector<Eigen::Vector3d> points;  // vertices in order, cloud units
  bool closed = false;                  // the last vertex joins the first (not repeated)
  /// Total length, the closing edge included when closed. Cloud units.
  double length() const;
};

}  // namespace pointsurf
