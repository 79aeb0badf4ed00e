// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The HTML report's page, written from its view model alone (html_report_view.h): the static
// tables, the PNG views as data URIs, and the one JSON payload the page's script builds the 3D
// view and the charts from, all filled into the template of page.h.
#include <string>

#include "report/detail/html_report_view.h"

namespace pointsurf::detail {

/// The page of `view`. Every text of the view is HTML-escaped (&, <, >, "); the payload and
/// the inlined libraries cannot end their <script> early ("</" written "<\/"). Numbers in the
/// tables: seconds to 3 decimals, MiB to 1. Thread-safe.
std::string render_html_report_page(const HtmlReportView& view);

}  // namespace pointsurf::detail
