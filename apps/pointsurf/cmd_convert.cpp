// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf convert IN OUT: any supported format to any other, as the pipeline [IN, OUT].
// Faces travel when both formats hold them.
#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/pipeline/registry.h"

namespace pointsurf::cli {
namespace {

std::string convert_help() {
  std::string out = "pointsurf convert IN OUT [options]\nConvert between formats; the output format follows OUT's extension.\n\n";
  out += "Formats: " + known_format_names(", ") + " (input detected from the content).\nOutput extensions: " + known_extensions(" ") + "\n\n";
  out += "Input and output options: those of 'pointsurf normals --help' (--columns, --input-format, --strict, --ascii, --float, --double,\n"
         "--big-endian, --compressed, --las-offset, --las-scale, --output-format).\n\n";
  out += common_options_help();
  out += "\nExample:\n  pointsurf convert data/kitten.xyz kitten.ply --ascii\n";
  return out;
}

int run_convert(const std::vector<std::string>& args) {
  CommonOptions common;
  std::vector<std::pair<std::string, std::string>> read_params, write_params;
  std::vector<OptionDef> options;
  auto add = [&](const StageSpec& s, std::vector<std::pair<std::string, std::string>>& target) {
    for (const ParamSpec& p : s.params) {
      if (p.name == "filename") continue;
      const std::string name = p.name == "format" ? (s.name == "read" ? "--input-format" : "--output-format") : dashed(p.name);
      options.push_back({name, p.type == ParamType::Bool, p.meta, [&target, key = p.name](const std::string& v) { target.emplace_back(key, v); }});
    }
  };
  add(*find_stage("read"), read_params);
  add(*find_stage("write"), write_params);
  add_common_options(options, common);
  const std::vector<std::string> positionals = scan_arguments(args, options);
  if (common.help) {
    fmt::print("{}", convert_help());
    return 0;
  }
  if (positionals.size() != 2) throw UsageError(fmt::format("expected IN OUT, got {} file names (see pointsurf convert --help)", positionals.size()));
  check_common_options(common);
  StepText read{"read", "in", {}, read_params}, write{"write", "out", {}, write_params};
  read.params.emplace_back("filename", positionals[0]);
  write.params.emplace_back("filename", positionals[1]);
  const Pipeline pipeline = build_with_report({read, write}, "convert", common, "convert");
  run_with_report(pipeline, common, "convert");
  return 0;
}

}  // namespace

Command convert_command() {
  return {"convert", "Convert between formats; the output format follows OUT's extension", run_convert, convert_help, cli_words};
}

}  // namespace pointsurf::cli
