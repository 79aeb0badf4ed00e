// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/polyline.h"

namespace pointsurf {

double Polyline::length() const {
  double sum = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) sum += (points[i] - points[i - 1]).norm();
  if (closed && points.size() > 2) sum += (points.front() - points.back()).norm();
  return sum;
}

}  // namespace pointsurf
