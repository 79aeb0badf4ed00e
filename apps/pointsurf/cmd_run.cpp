// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf run PIPELINE.json [--set STAGE.KEY=VALUE ...]: a whole chain in one process (one
// read, one kd-tree per cloud, no intermediate files unless asked).
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"

namespace pointsurf::cli {
namespace {

std::string run_help() {
  return "pointsurf run PIPELINE.json [--set STAGE.KEY=VALUE ...] [options]\n"
         "Run a pipeline: a JSON list of stages in PDAL's manner. A file name at the start reads, after a stage writes;\n"
         "an object has \"type\" (a stage: see pointsurf --help), the stage's keys (those of 'pointsurf STAGE --help'\n"
         "with _ for -), and optionally \"tag\" (the name of its output) and \"inputs\" (tags it reads).\n"
         "Everything is checked before any work; a malformed pipeline exits 1, a bad input file 2.\n\n"
         "Options:\n"
         "  --set STAGE.KEY=VALUE  Override or add a key; STAGE is a tag, or a type that occurs once (repeatable)\n"
         "  --html FILE.html       Also write the offline HTML report (as pointsurf report does)\n\n" +
         common_options_help() +
         "\nExample:\n"
         "  [\"scan.las\", {\"type\": \"clean\", \"method\": \"sor\"}, {\"type\": \"normals\", \"k\": 20},\n"
         "   {\"type\": \"reconstruct\", \"method\": \"ball-pivot\"}, \"mesh.ply\"]\n"
         "  pointsurf run examples/kitten_mesh.json --set normals.k=20 --report run.json\n";
}

int run_run(const std::vector<std::string>& args) {
  CommonOptions common;
  std::vector<std::string> sets;
  std::string html;
  std::vector<OptionDef> options = {{"--set", false, "STAGE.KEY=VALUE", [&](const std::string& v) { sets.push_back(v); }},
                                    {"--html", false, "FILE.html", [&](const std::string& v) { html = v; }}};
  add_common_options(options, common);
  const std::vector<std::string> positionals = scan_arguments(args, options);
  if (common.help) {
    fmt::print("{}", run_help());
    return 0;
  }
  if (positionals.size() != 1)
    throw UsageError(fmt::format("expected one PIPELINE.json, got {} file names (see pointsurf run --help)", positionals.size()));
  check_common_options(common);
  const std::string& file = positionals.front();
  std::ifstream in(file);
  if (!in) throw UsageError(fmt::format("{}: cannot read the pipeline", file));
  std::stringstream text;
  text << in.rdbuf();
  Pipeline pipeline;
  try {
    pipeline = parse_pipeline(text.str(), file, sets);
  } catch (const Error& e) {
    write_failure_report(common, "run", file, e);  // also when refused before any work
    throw;
  }
  if (!html.empty()) check_output_path(html, common.no_clobber, "html");
  std::string report;
  run_with_report(pipeline, common, "run", &report);
  if (!html.empty()) write_html_report(report, common.report_path.empty() ? file : common.report_path, html, {}, common);
  return 0;
}

}  // namespace

Command run_command() { return {"run", "Run a pipeline (JSON list of stages): pointsurf run PIPELINE.json", run_run, run_help, {}}; }

}  // namespace pointsurf::cli
