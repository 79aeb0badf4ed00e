// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The registry: every stage pointsurf offers, declared once (see stage.h), in data-flow order.
#include <string>
#include <string_view>
#include <vector>

#include "pointsurf/pipeline/stage.h"

namespace pointsurf {

/// All stages, in the order of the command list (data flow): read, crop, range, transform,
/// merge, clean, simplify, normals, curvature, features, reconstruct, quality, evaluate, write.
const std::vector<StageSpec>& registered_stages();
/// The stage named `name`, or nullptr.
const StageSpec* find_stage(std::string_view name);

/// The candidate closest to `word` by edit distance when it is close enough to be a typo
/// (at most a third of its length, at least 1, and at most 3 edits), else "".
std::string closest_name(std::string_view word, const std::vector<std::string>& candidates);

/// Parses `text` as a value of `spec` (the --set and command-line form: "30", "0.5", "true",
/// "mst", "1,2,3") and checks it against the range or choices. Throws UsageError with the
/// message "KEY: ..." (KEY = spec.name), e.g. `k: "abc" is not an integer`.
ParamValue parse_param_text(const ParamSpec& spec, const std::string& text);
/// Checks a value of the right type against the range or choices (UsageError "KEY: ...").
void check_param_value(const ParamSpec& spec, const ParamValue& value);

}  // namespace pointsurf
