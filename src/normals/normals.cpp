// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the normals implementation.
#include "pointsurf/normals/normals.h"
#include "pointsurf/core/error.h"
namespace pointsurf {
NormalResult estimate_normals(PointCloud&, const NormalParams&, const KdTree*, const ProgressCallback&) { throw ComputeError("missing"); }
OrientResult orient_normals(PointCloud&, const OrientParams&, const KdTree*, const ProgressCallback&) { throw ComputeError("missing"); }
}  // namespace pointsurf
