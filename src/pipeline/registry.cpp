// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/registry.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "pipeline/detail/declare.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

const std::vector<StageSpec>& registered_stages() {
  static const std::vector<StageSpec> stages = [] {
    std::vector<StageSpec> s = {detail::read_stage(),      detail::write_stage(),    detail::crop_stage(),
                                detail::range_stage(),     detail::transform_stage(), detail::merge_stage(),
                                detail::clean_stage(),     detail::simplify_stage(), detail::normals_stage(),
                                detail::curvature_stage(), detail::features_stage(), detail::segment_stage(), detail::boundary_stage(), detail::reconstruct_stage(),
                                detail::quality_stage(),   detail::evaluate_stage(),    detail::render_stage(),
                                detail::register_stage(),  detail::register_many_stage()};
    std::stable_sort(s.begin(), s.end(), [](const StageSpec& a, const StageSpec& b) { return a.order < b.order; });
    return s;
  }();
  return stages;
}

const StageSpec* find_stage(std::string_view name) {
  for (const StageSpec& s : registered_stages())
    if (s.name == name) return &s;
  return nullptr;
}

}  // namespace pointsurf
