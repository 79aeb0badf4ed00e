// SPDX-License-Identifier: GPL-3.0-or-later
// `pointsurf STAGE IN... OUT [--options]` for every registered stage, generated from the
// registry: options, --help with defaults, and the run as a one-stage pipeline
// [read IN, STAGE, write OUT], so the command and the pipeline give the same output.
#include <algorithm>
#include <map>
#include <set>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/registry.h"

namespace pointsurf::cli {
namespace {

// CLI spelling of a key of the reader or writer, which share "format".
std::string option_name(const std::string& stage, const std::string& key) {
  if (key == "format") return stage == "read" ? "--input-format" : "--output-format";
  return dashed(key);
}

// "  --option META   text", the text wrapped at 110 columns under its own column.
std::string help_row(const std::string& left, const std::string& text) {
  constexpr std::size_t indent = 33, width = 110;
  std::string out = fmt::format("  {:<30} ", left);
  if (out.size() > indent) out = "  " + left + "\n" + std::string(indent, ' ');
  std::size_t column = indent;
  std::size_t start = 0;
  while (start < text.size()) {
    std::size_t end = text.find(' ', start);
    if (end == std::string::npos) end = text.size();
    const std::string word = text.substr(start, end - start);
    if (column > indent && column + 1 + word.size() > width) {
      out += "\n" + std::string(indent, ' ');
      column = indent;
    } else if (column > indent) {
      out += ' ';
      ++column;
    }
    out += word;
    column += word.size();
    start = end + 1;
  }
  return out + "\n";
}

// The command's shape is the stage's declared CommandShape (pointsurf/pipeline/stage.h):
// Compare takes the reference as a file, read like the input.
bool takes_reference(const StageSpec& s) { return s.shape == CommandShape::Compare; }

// Pair: two inputs of equal standing (register: source, target): `STAGE A B [--out FILE]
// [--apply OUT]`, its own file (T.json) under --out and its product written by --apply.
bool takes_pair(const StageSpec& s) { return s.shape == CommandShape::Pair; }

// Picture: `STAGE IN OUT` where the stage writes OUT itself (render: a PNG).
bool own_file(const StageSpec& s) { return s.shape == CommandShape::Picture; }

// One help line per parameter declaration.
std::string param_line(const std::string& stage, const ParamSpec& p, bool show_methods) {
  std::string left = option_name(stage, p.name);
  if (p.type != ParamType::Bool) left += " " + (p.meta.empty() ? std::string("VALUE") : p.meta);
  std::vector<std::string> notes;
  const std::string def = format_value(p.default_value);
  if (p.type == ParamType::Bool) notes.push_back(fmt::format("default {}", def));
  else if (!def.empty()) notes.push_back("default " + def);
  if (!p.unit.empty()) notes.push_back(p.unit);
  if (p.has_range() && p.type != ParamType::Vector3) notes.push_back("range " + p.range_text());
  std::string methods;
  if (show_methods && !p.methods.empty()) {
    for (const std::string& m : p.methods) methods += (methods.empty() ? "" : ",") + m;
    methods = "[" + methods + "] ";
  }
  std::string n;
  for (const std::string& s : notes) n += (n.empty() ? "" : "; ") + s;
  return help_row(left, methods + p.doc + (n.empty() ? "" : " (" + n + ")"));
}

std::string stage_help(const StageSpec& s) {
  const bool multi = s.takes_many();
  const bool own_file = pointsurf::cli::own_file(s);
  std::string out = command_synopsis(s) + "\n" + s.summary + "\n";
  if (!s.description.empty()) out += s.description + "\n";
  if (!s.params.empty() || !s.methods.empty()) out += "\nOptions (pipeline keys are the same with _ for -):\n";
  if (!s.methods.empty()) {
    std::string list;
    for (const std::string& m : s.methods) list += (list.empty() ? "" : "|") + m;
    out += help_row("--method " + list,
                    fmt::format("{} (default {})", s.method_list ? "Comma-separated methods, applied in order" : "Method", s.default_method));
  }
  for (const ParamSpec& p : s.params) {
    if (own_file && p.name == s.writes_param) continue;  // OUT
    if (s.measures() && p.name == "reference") out += help_row("--reference FILE", "The cloud or mesh to measure (required)");
    else out += param_line(s.name, p, !s.methods.empty());
  }
  if (s.measures()) out += help_row("--out FILE", "Write the result (evaluate: the reference with a field deviation)");
  if (takes_pair(s)) out += help_row("--apply OUT", fmt::format("Write the {}'s product (the moved {})", s.name, s.consumes[0].name));
  if (multi) out += help_row("--out OUT", "The output file, when every file name given is an input");
  out += "\nInput options:\n";
  for (const ParamSpec& p : find_stage("read")->params)
    if (p.name != "filename") out += param_line("read", p, false);
  if (!own_file) out += "\nOutput options:\n";
  for (const ParamSpec& p : find_stage("write")->params)
    if (p.name != "filename" && !own_file) out += param_line("write", p, false);
  out += "\n";
  out += common_options_help();
  if (!s.examples.empty()) {
    out += "\nExamples:\n";
    for (const std::string& e : s.examples) out += "  " + e + "\n";
  }
  return out;
}

using KeyValues = std::vector<std::pair<std::string, std::string>>;

// Builds and runs a checked pipeline for one command, in the command line's words.
void run_steps(const StageSpec& s, const std::vector<StepText>& steps, const CommonOptions& common) {
  const Pipeline pipeline = build_with_report(steps, "cli", common, s.name);
  run_with_report(pipeline, common, s.name);
}

// `pointsurf evaluate MESH --reference FILE [--out FILE]`, `pointsurf quality MESH [--out FILE]`:
// [read IN, read reference, STAGE, write --out].
int run_measure(const StageSpec& s, const std::vector<std::string>& positionals, const std::string& reference_file,
                const std::string& out_file, const KeyValues& stage_params, const KeyValues& read_params, const KeyValues& write_params,
                const CommonOptions& common) {
  if (positionals.size() != 1)
    throw UsageError(fmt::format("expected one input file IN, got {} file names (see pointsurf {} --help)", positionals.size(), s.name));
  if (takes_reference(s) && reference_file.empty())
    throw UsageError(fmt::format("--reference FILE is required (see pointsurf {} --help)", s.name));
  check_common_options(common);
  std::vector<StepText> steps;
  StepText read{"read", "in1", {}, read_params};
  read.params.emplace_back("filename", positionals.front());
  steps.push_back(std::move(read));
  std::vector<std::string> inputs = {"in1"};
  if (takes_reference(s)) {
    StepText ref{"read", "reference", {}, read_params};
    ref.params.emplace_back("filename", reference_file);
    steps.push_back(std::move(ref));
    inputs.push_back("reference");
  }
  steps.push_back(StepText{s.name, s.name, inputs, stage_params});
  if (!out_file.empty()) {
    StepText write{"write", "out", {}, write_params};
    write.params.emplace_back("filename", out_file);
    steps.push_back(std::move(write));
  }
  run_steps(s, steps, common);
  return 0;
}

// `pointsurf register SOURCE TARGET [--out T.json] [--apply MOVED]`: [read SOURCE, read TARGET,
// STAGE (writing its own file), write --apply].
int run_pair(const StageSpec& s, const std::vector<std::string>& positionals, const std::string& apply_file, const KeyValues& stage_params,
             const KeyValues& read_params, const KeyValues& write_params, const CommonOptions& common) {
  if (positionals.size() != 2)
    throw UsageError(fmt::format("expected two input files {} {}, got {} file name{} (see pointsurf {} --help)", s.consumes[0].name, s.consumes[1].name,
                                 positionals.size(), positionals.size() == 1 ? "" : "s", s.name));
  const bool own = std::any_of(stage_params.begin(), stage_params.end(), [&](const auto& kv) { return kv.first == s.writes_param && !kv.second.empty(); });
  if (!own && apply_file.empty())
    throw UsageError(fmt::format("nothing to write: give {} FILE, --apply OUT or both (see pointsurf {} --help)", dashed(s.writes_param), s.name));
  check_common_options(common);
  auto file_step = [](const char* type, const std::string& tag, const KeyValues& params, const std::string& file) {
    StepText step{type, tag, {}, params};
    step.params.emplace_back("filename", file);
    return step;
  };
  std::vector<StepText> steps = {file_step("read", s.consumes[0].name, read_params, positionals[0]),
                                 file_step("read", s.consumes[1].name, read_params, positionals[1]),
                                 StepText{s.name, s.name, {s.consumes[0].name, s.consumes[1].name}, stage_params}};
  if (!apply_file.empty()) steps.push_back(file_step("write", "out", write_params, apply_file));
  run_steps(s, steps, common);
  return 0;
}

int run_stage(const StageSpec& s, const std::vector<std::string>& args) {
  CommonOptions common;
  std::vector<OptionDef> options;
  // Values as given, per owner (stage, read, write): the pipeline parses and checks them.
  std::vector<std::pair<std::string, std::string>> stage_params, read_params, write_params;
  std::set<std::string> seen;
  auto add = [&](const std::string& owner, const ParamSpec& p, std::vector<std::pair<std::string, std::string>>& target) {
    const std::string name = option_name(owner, p.name);
    if (!seen.insert(name).second) return;
    options.push_back({name, p.type == ParamType::Bool, p.meta, [&target, key = p.name, name](const std::string& v) {
                         for (const auto& kv : target)
                           if (kv.first == key) throw UsageError(fmt::format("{} given twice", name));
                         target.emplace_back(key, v);
                       }});
    // Former keys (one release): passed on as written; the pipeline maps them and warns.
    for (const std::string& old : p.old_names) {
      const std::string old_name = option_name(owner, old);
      if (!seen.insert(old_name).second) continue;
      options.push_back({old_name, p.type == ParamType::Bool, p.meta,
                         [&target, old](const std::string& v) { target.emplace_back(old, v); }});
    }
  };
  if (!s.methods.empty())
    options.push_back({"--method", false, "METHOD", [&](const std::string& v) {
                         for (const auto& kv : stage_params)
                           if (kv.first == "method") throw UsageError("--method given twice");
                         stage_params.emplace_back("method", v);
                       }});
  std::string reference_file, out_file;
  if (s.measures()) {
    options.push_back({"--out", false, "FILE", [&](const std::string& v) {
                         if (!out_file.empty()) throw UsageError("--out given twice");
                         out_file = v;
                       }});
    seen.insert("--out");
    if (takes_reference(s)) {
      options.push_back({"--reference", false, "FILE", [&](const std::string& v) {
                           if (!reference_file.empty()) throw UsageError("--reference given twice");
                           reference_file = v;
                         }});
      seen.insert("--reference");
    }
  }
  const bool own_file = pointsurf::cli::own_file(s);
  const bool multi = s.takes_many();
  for (const ParamSpec& p : s.params)
    if (!own_file || p.name != s.writes_param) add(s.name, p, stage_params);
  std::string apply_file, multi_out;
  if (takes_pair(s)) {
    options.push_back({"--apply", false, "OUT", [&](const std::string& v) {
                         if (!apply_file.empty()) throw UsageError("--apply given twice");
                         apply_file = v;
                       }});
    seen.insert("--apply");
  }
  if (multi && s.find_param("out") == nullptr) {
    options.push_back({"--out", false, "OUT", [&](const std::string& v) {
                         if (!multi_out.empty()) throw UsageError("--out given twice");
                         multi_out = v;
                       }});
    seen.insert("--out");
  }
  for (const ParamSpec& p : find_stage("read")->params)
    if (p.name != "filename") add("read", p, read_params);
  for (const ParamSpec& p : find_stage("write")->params)
    if (p.name != "filename" && !own_file) add("write", p, write_params);
  add_common_options(options, common);

  std::vector<std::string> positionals;
  try {
    positionals = scan_arguments(args, options);
  } catch (const UsageError& e) {
    throw UsageError(std::string(e.what()) + fmt::format(" (see pointsurf {} --help)", s.name));
  }
  if (common.help) {
    fmt::print("{}", stage_help(s));
    return 0;
  }
  switch (s.shape) {
    case CommandShape::Compare:
    case CommandShape::Measure:
      return run_measure(s, positionals, reference_file, out_file, stage_params, read_params, write_params, common);
    case CommandShape::Pair:
      return run_pair(s, positionals, apply_file, stage_params, read_params, write_params, common);
    case CommandShape::Read:
    case CommandShape::Write:
      throw UsageError(fmt::format("{} is a pipeline stage without a command (see pointsurf convert)", s.name));
    case CommandShape::Transform:
    case CommandShape::Merge:
    case CommandShape::Picture:
      break;
  }
  if (!multi_out.empty()) positionals.push_back(multi_out);
  if (positionals.size() < (multi ? 3u : 2u) || (!multi && positionals.size() > 2))
    throw UsageError(fmt::format("expected {} OUT, got {} file name{} (see pointsurf {} --help)", multi ? "IN1 IN2 [IN...]" : "IN",
                                 positionals.size(), positionals.size() == 1 ? "" : "s", s.name));
  check_common_options(common);
  std::vector<StepText> steps;
  std::vector<std::string> inputs;
  for (std::size_t i = 0; i + 1 < positionals.size(); ++i) {
    StepText read{"read", fmt::format("in{}", i + 1), {}, read_params};
    read.params.emplace_back("filename", positionals[i]);
    inputs.push_back(read.tag);
    steps.push_back(std::move(read));
  }
  StepText stage{s.name, s.name, multi ? inputs : std::vector<std::string>{}, stage_params};
  if (own_file) {  // render IN OUT.png: the stage writes OUT itself
    stage.params.emplace_back(s.writes_param, positionals.back());
    steps.push_back(std::move(stage));
    run_steps(s, steps, common);
    return 0;
  }
  steps.push_back(std::move(stage));
  StepText write{"write", "out", {}, write_params};
  write.params.emplace_back("filename", positionals.back());
  steps.push_back(std::move(write));
  run_steps(s, steps, common);
  return 0;
}

}  // namespace

// An error in the command line's words (core/error.h): no stage prefix, since the command is the
// stage, and a parameter named as its option ("--k: 0 is out of range [1, inf)").
std::string cli_words(const Error& e) {
  const ErrorPlace& at = e.place();
  const std::string& m = e.message();
  if (!at.key.empty() && m.compare(0, at.key.size(), at.key) == 0) {
    const StageSpec* owner = find_stage(at.stage);
    if (owner != nullptr && (owner->find_param(at.key) != nullptr || at.key == "method"))
      return option_name(at.stage, at.key) + m.substr(at.key.size());
  }
  return m;
}

std::vector<Command> stage_commands() {
  std::vector<Command> out;
  for (const StageSpec& s : registered_stages()) {
    if (s.shape == CommandShape::Read || s.shape == CommandShape::Write) continue;
    out.push_back({s.name, s.summary, [&s](const std::vector<std::string>& args) { return run_stage(s, args); }, [&s] { return stage_help(s); },
                   cli_words});
  }
  return out;
}

}  // namespace pointsurf::cli
