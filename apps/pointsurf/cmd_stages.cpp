// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf stages [--markdown]: the registry's stages, one line each, or docs/stages.md.
#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/registry.h"

namespace pointsurf::cli {
namespace {

std::string stages_help() {
  return "pointsurf stages [--markdown]\n"
         "List the stages; with --markdown, print every stage's parameters as docs/stages.md holds them.\n\n"
         "Example:\n  pointsurf stages --markdown > docs/stages.md\n";
}

int run_stages(const std::vector<std::string>& args) {
  bool markdown = false, help = false;
  const std::vector<OptionDef> options = {{"--markdown", true, "", [&](const std::string& v) { markdown = v == "true"; }},
                                          {"--help", true, "", [&](const std::string& v) { help = v == "true"; }}};
  const std::vector<std::string> positionals = scan_arguments(args, options);
  if (help) {
    fmt::print("{}", stages_help());
    return 0;
  }
  if (!positionals.empty()) throw UsageError(fmt::format("expected no file names, got {} (see pointsurf stages --help)", positionals.size()));
  if (markdown) {
    fmt::print("{}", stages_markdown());
    return 0;
  }
  for (const StageSpec& s : registered_stages()) fmt::print("{:<14} {}\n", s.name, s.summary);
  return 0;
}

}  // namespace

Command stages_command() { return {"stages", "List the stages (--markdown: docs/stages.md)", run_stages, stages_help, {}}; }

}  // namespace pointsurf::cli
