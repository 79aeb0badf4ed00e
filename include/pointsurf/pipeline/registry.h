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

/// docs/stages.md: every stage with its command shape, methods, parameters (key, type, unit,
/// default, range or choices, doc, former keys) and examples, as Markdown generated from the
/// registry (`pointsurf stages --markdown` prints it; a test checks the committed file).
std::string stages_markdown();

}  // namespace pointsurf
