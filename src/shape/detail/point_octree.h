// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// An octree over points in Morton order for detect_primitives: cells keep the bounding sphere
// of their points and a count of the points not yet assigned, so that scoring a primitive only
// visits cells its epsilon band reaches (Schnabel et al. 2007, section 4.3) and skips emptied
// ones.
#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace pointsurf::detail {

class PointOctree {
public:
  /// Over the points `ranks` (ascending, so in Morton order) of `pts`, with their Morton
  /// codes `codes` (indexed by rank, `bits` per axis). Leaves hold at most `leaf_size` points.
  /// `leaf_of[rank]` is set to each point's leaf, for `remove`.
  PointOctree(std::vector<std::uint32_t> ranks, const std::vector<Eigen::Vector3d>& pts, const std::vector<std::uint64_t>& codes, int bits,
              std::vector<std::uint32_t>& leaf_of, std::uint32_t leaf_size = 16)
      : ranks_(std::move(ranks)) {
    if (ranks_.empty()) return;
    nodes_.push_back({0, std::uint32_t(ranks_.size()), 0, 0, 0, std::uint32_t(ranks_.size()), 0.0, Eigen::Vector3d::Zero()});
    std::vector<int> level(1, 0);
    for (std::size_t i = 0; i < nodes_.size(); ++i) {
      const std::uint32_t begin = nodes_[i].begin, end = nodes_[i].end;
      if (end - begin <= leaf_size || level[i] >= bits) continue;
      const int shift = 3 * (bits - level[i] - 1);
      nodes_[i].first_child = std::uint32_t(nodes_.size());
      for (std::uint32_t b = begin; b < end;) {
        const std::uint64_t digit = codes[ranks_[b]] >> shift;
        std::uint32_t e = b + 1;
        while (e < end && (codes[ranks_[e]] >> shift) == digit) ++e;
        nodes_.push_back({b, e, 0, 0, std::uint32_t(i), e - b, 0.0, Eigen::Vector3d::Zero()});
        level.push_back(level[i] + 1);
        ++nodes_[i].children;
        b = e;
      }
    }
    // Bounding boxes bottom-up (children follow their parent), then their spheres.
    std::vector<Eigen::Vector3d> lo(nodes_.size()), hi(nodes_.size());
    for (std::size_t i = nodes_.size(); i-- > 0;) {
      Node& node = nodes_[i];
      if (node.children == 0) {
        lo[i] = hi[i] = pts[ranks_[node.begin]];
        for (std::uint32_t j = node.begin; j < node.end; ++j) {
          lo[i] = lo[i].cwiseMin(pts[ranks_[j]]);
          hi[i] = hi[i].cwiseMax(pts[ranks_[j]]);
        }
        for (std::uint32_t j = node.begin; j < node.end; ++j) leaf_of[ranks_[j]] = std::uint32_t(i);
      } else {
        lo[i] = lo[node.first_child];
        hi[i] = hi[node.first_child];
        for (std::uint32_t c = node.first_child; c < node.first_child + node.children; ++c) {
          lo[i] = lo[i].cwiseMin(lo[c]);
          hi[i] = hi[i].cwiseMax(hi[c]);
        }
      }
      node.centre = 0.5 * (lo[i] + hi[i]);
      node.radius = 0.5 * (hi[i] - lo[i]).norm();
    }
  }

  bool empty() const { return nodes_.empty(); }
  std::size_t alive() const { return nodes_.empty() ? 0 : nodes_[0].alive; }

  /// Calls leaf(first, last) on the rank ranges of the leaves that may hold a point within
  /// `reach` of the primitive whose 1-Lipschitz distance is `distance(x)`, in Morton order.
  template <class Distance, class Leaf>
  void visit(const Distance& distance, double reach, const Leaf& leaf) const {
    walk(distance, reach, [&](std::uint32_t i) { leaf(leaf_begin(i), leaf_end(i)); });
  }

  /// The leaves of `visit` in `out` (replaced), for parallel loops over them.
  template <class Distance>
  void leaves(const Distance& distance, double reach, std::vector<std::uint32_t>& out) const {
    out.clear();
    walk(distance, reach, [&](std::uint32_t i) { out.push_back(i); });
  }

  /// The ranks of leaf `i` (from `leaves`).
  const std::uint32_t* leaf_begin(std::uint32_t i) const { return ranks_.data() + nodes_[i].begin; }
  const std::uint32_t* leaf_end(std::uint32_t i) const { return ranks_.data() + nodes_[i].end; }

  /// Counts a point of leaf `leaf` (from the constructor's `leaf_of`) as assigned.
  void remove(std::uint32_t leaf) {
    for (std::uint32_t i = leaf;; i = nodes_[i].parent) {
      --nodes_[i].alive;
      if (i == 0) break;
    }
  }

private:
  template <class Distance, class Leaf>
  void walk(const Distance& distance, double reach, const Leaf& leaf) const {
    if (nodes_.empty() || nodes_[0].alive == 0) return;
    std::uint32_t stack[8 * 64];  // at most 8 children a level, 21 levels
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const std::uint32_t i = stack[--top];
      const Node& node = nodes_[i];
      if (node.alive == 0 || distance(node.centre) > node.radius + reach) continue;
      if (node.children == 0) {
        leaf(i);
        continue;
      }
      for (std::uint32_t c = node.first_child + node.children; c-- > node.first_child;) stack[top++] = c;
    }
  }

  struct Node {
    std::uint32_t begin, end;   // range in ranks_
    std::uint32_t first_child;  // children are contiguous
    std::uint32_t children;
    std::uint32_t parent;
    std::uint32_t alive;  // points not yet assigned
    double radius;        // bounding sphere of the points
    Eigen::Vector3d centre;
  };
  std::vector<std::uint32_t> ranks_;
  std::vector<Node> nodes_;
};

}  // namespace pointsurf::detail
