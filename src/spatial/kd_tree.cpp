// SPDX-License-Identifier: GPL-3.0-or-later
// PLACEHOLDER: replaced by the spatial implementation.
#include "pointsurf/spatial/kd_tree.h"
#include "pointsurf/core/error.h"
namespace pointsurf {
struct KdTree::Impl {};
KdTree::KdTree(std::span<const Eigen::Vector3d>, int) { throw ComputeError("kd-tree missing"); }
KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;
}  // namespace pointsurf
