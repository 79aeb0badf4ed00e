// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <unordered_map>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/segment/segment.h"

namespace pointsurf {

SegmentResult number_segments(std::span<const Eigen::Vector3d> positions, std::span<const std::int64_t> groups, std::size_t min_points) {
  if (positions.size() != groups.size())
    throw UsageError(fmt::format("number_segments: {} positions but {} group ids", positions.size(), groups.size()));
  struct Group {
    std::size_t size = 0;
    std::size_t smallest = 0;  // index of its lexicographically smallest point
  };
  auto less = [&](std::size_t a, std::size_t b) {
    return std::lexicographical_compare(positions[a].data(), positions[a].data() + 3, positions[b].data(), positions[b].data() + 3);
  };
  std::unordered_map<std::int64_t, Group> found;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    if (groups[i] < 0) continue;
    auto [it, added] = found.try_emplace(groups[i], Group{0, i});
    ++it->second.size;
    if (less(i, it->second.smallest)) it->second.smallest = i;
  }
  std::vector<std::pair<std::int64_t, Group>> order(found.begin(), found.end());
  std::sort(order.begin(), order.end(), [&](const auto& a, const auto& b) {
    if (a.second.size != b.second.size) return a.second.size > b.second.size;
    return less(a.second.smallest, b.second.smallest);
  });
  std::unordered_map<std::int64_t, std::int32_t> number;
  SegmentResult result;
  for (const auto& [id, g] : order) {
    if (g.size < std::max<std::size_t>(min_points, 1)) break;
    number[id] = std::int32_t(result.sizes.size());
    result.sizes.push_back(g.size);
  }
  result.labels.assign(groups.size(), -1);
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const auto it = groups[i] < 0 ? number.end() : number.find(groups[i]);
    if (it != number.end()) result.labels[i] = it->second;
    else ++result.unassigned;
  }
  return result;
}

}  // namespace pointsurf
