// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small helpers the stage run functions share.
#include <cstddef>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/pipeline/stage.h"

namespace pointsurf::detail {

/// "1 point", "2 points".
inline std::string plural(std::size_t n, const std::string& singular, const std::string& plural_form = {}) {
  return fmt::format("{} {}", n, n == 1 ? singular : (plural_form.empty() ? singular + "s" : plural_form));
}

/// A stage that changes the point set of a mesh cannot keep its faces: drop them and say so.
inline void drop_faces(DataItem& item, StageRecord& record) {
  if (item.mesh.triangles.empty() && !item.is_mesh) return;
  if (!item.mesh.triangles.empty())
    record.warnings.push_back(fmt::format("the input is a mesh: its {} are dropped ({} works on points)",
                                          plural(item.mesh.triangles.size(), "face"), record.type));
  item.mesh.triangles.clear();
  item.mesh.face_fields = FieldSet{};
  item.is_mesh = false;
}

inline std::int64_t as_count(std::size_t n) { return static_cast<std::int64_t>(n); }

}  // namespace pointsurf::detail

namespace pointsurf::detail {

/// A callback for one part [begin, end] of a stage's progress (empty when `whole` is); phase
/// names pass through (pointsurf::sub_progress).
inline ProgressCallback sub_progress(const ProgressCallback& whole, double begin, double end, std::string_view phase = {}) {
  return pointsurf::sub_progress(whole, begin, end, phase);
}

/// Reports entering `phase` (when given) and the fraction `f` of the stage to `progress`; throws
/// CancelledError when it asks to stop.
inline void report_progress(const ProgressCallback& progress, double f, std::string_view phase = {}) {
  if (!progress) return;
  if (!phase.empty()) report_phase(progress, phase);
  if (!progress(f)) throw CancelledError();
}

/// Name of a neighbourhood kind as the parameter "neighborhood" spells it.
inline const char* neighborhood_name(int kind) { return kind == 0 ? "knn" : kind == 1 ? "radius" : "hybrid"; }

}  // namespace pointsurf::detail
