// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The report page's template: HTML, CSS and the page's own JavaScript, with {{SLOT}} markers.
#include <map>
#include <string>

namespace pointsurf::detail {

/// The template with each {{NAME}} replaced by slots.at(NAME) (a missing slot stays empty).
/// Inlined scripts (slots ending in _JS) get "</script" written "<\/script" so they cannot end
/// their element early.
std::string fill_page(const std::map<std::string, std::string>& slots);

}  // namespace pointsurf::detail
