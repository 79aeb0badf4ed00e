// SPDX-License-Identifier: GPL-3.0-or-later
// Checking a pipeline against the registry (everything before any work) and running it.
#include "pointsurf/pipeline/pipeline.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>

#include <fmt/format.h>

#include "pipeline/detail/raw_step.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/registry.h"

namespace pointsurf {

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
}

namespace {

using detail::RawStep;
using detail::RawValue;

const char* raw_kind_name(const RawValue& v) {
  switch (v.kind) {
    case RawValue::Kind::Bool: return "a boolean";
    case RawValue::Kind::Int: return "an integer";
    case RawValue::Kind::Double: return "a number";
    case RawValue::Kind::String: return "a string";
    case RawValue::Kind::Numbers: return "a list of numbers";
    case RawValue::Kind::Strings: return "a list of strings";
    default: return v.s.c_str();
  }
}

// Converts a written value to the parameter's type; UsageError "KEY: ..." on a mismatch.
ParamValue convert(const ParamSpec& spec, const RawValue& raw) {
  if (raw.kind == RawValue::Kind::Text) return parse_param_text(spec, raw.s);
  auto mismatch = [&] {
    return key_error(spec.name, fmt::format("expected {}, got {}",
                                  spec.type == ParamType::Int ? "an integer" : spec.type == ParamType::Double ? "a number"
                                  : spec.type == ParamType::Bool ? "true or false" : param_type_name(spec.type),
                                  raw_kind_name(raw)));
  };
  ParamValue value;
  switch (spec.type) {
    case ParamType::Bool:
      if (raw.kind != RawValue::Kind::Bool) throw mismatch();
      value = raw.b;
      break;
    case ParamType::Int:
      if (raw.kind == RawValue::Kind::Int) value = raw.i;
      else if (raw.kind == RawValue::Kind::Double && raw.d == std::floor(raw.d) && std::abs(raw.d) < 9e15) value = static_cast<std::int64_t>(raw.d);
      else throw mismatch();
      break;
    case ParamType::Double:
      if (raw.kind != RawValue::Kind::Int && raw.kind != RawValue::Kind::Double) throw mismatch();
      value = raw.d;
      break;
    case ParamType::String:
    case ParamType::Choice:
      if (raw.kind != RawValue::Kind::String) throw mismatch();
      value = raw.s;
      break;
    case ParamType::ChoiceList:
      if (raw.kind == RawValue::Kind::String) {
        value = raw.s;
      } else if (raw.kind == RawValue::Kind::Strings) {
        std::string joined;
        for (const std::string& s : raw.strings) joined += (joined.empty() ? "" : ",") + s;
        value = joined;
      } else {
        throw mismatch();
      }
      break;
    case ParamType::Length:
      if (raw.kind == RawValue::Kind::Int || raw.kind == RawValue::Kind::Double) value = Length::cloud(raw.d);
      else if (raw.kind == RawValue::Kind::String) value = Length::parse(raw.s, spec.name);
      else throw mismatch();
      break;
    case ParamType::Vector3:
    case ParamType::DoubleList:
      if (raw.kind == RawValue::Kind::Numbers) value = raw.numbers;
      else if (raw.kind == RawValue::Kind::Int || raw.kind == RawValue::Kind::Double) {
        if (spec.type == ParamType::Vector3) throw mismatch();
        value = std::vector<double>{raw.d};
      } else {
        throw mismatch();
      }
      if (spec.type == ParamType::Vector3 && std::get<std::vector<double>>(value).size() != 3)
        throw key_error(spec.name, fmt::format("expected 3 numbers [X, Y, Z], got {}", std::get<std::vector<double>>(value).size()));
      break;
  }
  check_param_value(spec, value);
  return value;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) out.push_back(item);
  return out;
}

std::string join(const std::vector<std::string>& items, const char* separator = ", ") {
  std::string out;
  for (const std::string& s : items) out += (out.empty() ? "" : separator) + s;
  return out;
}

bool is_writer(const PipelineStep& s) { return s.spec->shape == CommandShape::Write; }
bool is_reader(const PipelineStep& s) { return s.spec->shape == CommandShape::Read; }

// Resolves the parameters of one method (or, for a method list, of all listed ones, used to
// check that each given key belongs to one of them).
StageArgs resolve(const StageSpec& spec, const std::vector<std::string>& methods, const std::string& method_value,
                  const std::map<std::string, ParamValue>& given_values) {
  std::map<std::string, ParamValue> values;
  std::map<std::string, bool> given;
  for (const ParamSpec& p : spec.params) {
    const bool applies = methods.empty() || std::any_of(methods.begin(), methods.end(), [&](const std::string& m) { return p.applies_to(m); });
    if (!applies || values.count(p.name)) continue;
    const auto it = given_values.find(p.name);
    values[p.name] = it != given_values.end() ? it->second : p.default_value;
    given[p.name] = it != given_values.end();
  }
  if (!spec.methods.empty()) {
    values["method"] = method_value;
    given["method"] = given_values.count("method") > 0;
  }
  return StageArgs(std::move(values), std::move(given), method_value);
}

class Builder {
public:
  explicit Builder(std::string origin) : origin_(std::move(origin)) {}

  Pipeline build(std::vector<RawStep> raw, const std::vector<std::string>& overrides) {
    // Readers and writers: a bare file name reads while only readers came before it.
    bool data_stage_seen = false;
    for (RawStep& r : raw) {
      if (r.is_file) {
        r.type = data_stage_seen ? "write" : "read";
        RawValue v;
        v.kind = RawValue::Kind::String;
        v.s = r.file;
        r.params.emplace_back("filename", v);
      }
      if (r.type != "read") data_stage_seen = true;
    }
    apply_overrides(raw, overrides);
    Pipeline p;
    p.origin = origin_;
    std::vector<std::string> open;        // outputs no stage has read yet
    std::string last;                     // the latest output
    std::set<std::string> tags;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const RawStep& r = raw[i];
      const StageSpec* spec = find_stage(r.type);
      // Errors of this stage name it (origin, position, type) as data; see core/error.h.
      auto fail = [&](std::string text, std::string key = {}) {
        UsageError e(std::move(text));
        if (!key.empty()) e.set_key(std::move(key));
        e.set_stage(origin_, i + 1, r.type);
        return e;
      };
      auto name_stage = [&](Error& e) { e.set_stage(origin_, i + 1, r.type); };
      if (spec == nullptr) {
        std::vector<std::string> names;
        for (const StageSpec& s : registered_stages()) names.push_back(s.name);
        const std::string near = closest_name(r.type, names);
        throw fail(fmt::format("unknown stage type \"{}\"{}", r.type,
                                     near.empty() ? fmt::format(" (stages: {})", join(names)) : fmt::format("; did you mean \"{}\"?", near)));
      }
      PipelineStep step;
      step.spec = spec;
      // Parameters: known keys, right types, in range, of the chosen method.
      std::map<std::string, ParamValue> given;
      std::string method = spec->default_method;
      for (const auto& [key, value] : r.params) {
        if (key == "method" && !spec->methods.empty()) {
          ParamSpec m;
          m.name = "method";
          m.type = spec->method_list ? ParamType::ChoiceList : ParamType::Choice;
          m.choices = spec->methods;
          try {
            method = std::get<std::string>(convert(m, value));
          } catch (UsageError& e) {
            name_stage(e);
            throw;
          }
          given["method"] = method;
        }
      }
      const std::vector<std::string> methods = spec->methods.empty() ? std::vector<std::string>{} : spec->method_list ? split_list(method)
                                                                                                                    : std::vector<std::string>{method};
      for (const auto& [written_key, written_value] : r.params) {
        if (written_key == "method" && !spec->methods.empty()) continue;
        std::string key = written_key;
        RawValue value = written_value;
        if (spec->params_named(key).empty() && !spec->params_formerly(key).empty()) {
          // A key of the previous release: its parameter's new key, with a warning. A former
          // "X_in_spacings" number is a length in spacings; a former cloud-units length of 0
          // meant "the default in spacings".
          const ParamSpec* now = spec->params_formerly(key).front();
          const bool in_spacings = key.size() > 12 && key.compare(key.size() - 12, 12, "_in_spacings") == 0;
          step.warnings.push_back(fmt::format("key \"{}\" is deprecated: use \"{}\"{} (the old key goes in the next release)", key,
                                              now->name, in_spacings ? " with a value in spacings, e.g. \"3sp\"" : ""));
          if (now->type == ParamType::Length && (value.kind == RawValue::Kind::Int || value.kind == RawValue::Kind::Double ||
                                                 value.kind == RawValue::Kind::Text)) {
            double d = value.d;
            if (value.kind == RawValue::Kind::Text) {
              try {
                d = std::stod(value.s);
              } catch (const std::exception&) {
                throw fail(fmt::format("{}: \"{}\" is not a number", key, value.s), key);
              }
            }
            if (!in_spacings && d == 0.0) continue;
            value = RawValue{};
            value.kind = RawValue::Kind::String;
            value.s = Length{d, in_spacings ? Length::Unit::Spacings : Length::Unit::Cloud}.text();
          }
          key = now->name;
        }
        if (given.count(key)) throw fail(fmt::format("key \"{}\" given twice", key), key);
        const std::vector<const ParamSpec*> candidates = spec->params_named(key);
        if (candidates.empty()) {
          std::vector<std::string> keys = {"type", "tag", "inputs"};
          if (!spec->methods.empty()) keys.push_back("method");
          for (const ParamSpec& ps : spec->params) keys.push_back(ps.name);
          const std::string near = closest_name(key, keys);
          throw fail(fmt::format("unknown key \"{}\"{}", key, near.empty() ? "" : fmt::format("; did you mean \"{}\"?", near)), key);
        }
        const ParamSpec* applicable = nullptr;
        for (const ParamSpec* c : candidates)
          if (methods.empty() || std::any_of(methods.begin(), methods.end(), [&](const std::string& m) { return c->applies_to(m); }))
            applicable = applicable ? applicable : c;
        if (applicable == nullptr) {
          std::vector<std::string> owners;
          for (const ParamSpec* c : candidates) owners.insert(owners.end(), c->methods.begin(), c->methods.end());
          throw fail(fmt::format("{} belongs to method {}, not to method {}", key, join(owners, " or "), method), key);
        }
        try {
          given[key] = convert(*applicable, value);
        } catch (UsageError& e) {
          name_stage(e);
          throw;
        }
      }
      step.args = resolve(*spec, methods, method, given);
      if (spec->method_list)
        for (const std::string& m : methods) step.per_method.push_back(resolve(*spec, {m}, m, given));
      else
        step.per_method.push_back(step.args);
      if (spec->check) {
        try {
          for (const StageArgs& a : step.per_method) spec->check(a);
        } catch (UsageError& e) {
          name_stage(e);
          throw;
        }
      }

      // Tag and inputs.
      step.tag = r.has_tag ? r.tag : fmt::format("{}{}", r.type, i + 1);
      if (!tags.insert(step.tag).second) throw fail(fmt::format("tag \"{}\" is used twice", step.tag));
      const bool multi = spec->takes_many();
      if (r.has_inputs && spec->consumes.empty())
        throw fail("takes no \"inputs\" (it reads a file)");
      if (r.has_inputs) {
        for (const std::string& in : r.inputs)
          if (!known_.count(in)) {
            std::vector<std::string> k(known_.begin(), known_.end());
            const std::string near = closest_name(in, k);
            throw fail(fmt::format("input \"{}\" is not the tag of an earlier stage{}", in,
                                         near.empty() ? (k.empty() ? "" : fmt::format(" (tags so far: {})", join(k)))
                                                      : fmt::format("; did you mean \"{}\"?", near)));
          }
        step.inputs = r.inputs;
      } else if (!spec->consumes.empty()) {
        if (multi) step.inputs = open;
        else if (!last.empty()) step.inputs = {last};
      }
      if (spec->shape == CommandShape::Compare && step.inputs.size() == 1) {
        // The reference: the tag the stage names, else the cloud as read before the chain.
        const std::string named = step.args.has("reference") ? step.args.text("reference") : std::string();
        if (!named.empty() && !known_.count(named)) {
          std::vector<std::string> k(known_.begin(), known_.end());
          const std::string near = closest_name(named, k);
          throw fail(fmt::format("reference \"{}\" is not the tag of an earlier stage{}", named,
                                       near.empty() ? fmt::format(" (tags so far: {})", join(k)) : fmt::format("; did you mean \"{}\"?", near)));
        }
        step.inputs.push_back(named.empty() ? origin_of_[step.inputs.front()] : named);
      }
      if (spec->name == "read" || step.inputs.size() != 1) origin_of_[step.tag] = step.tag;
      else origin_of_[step.tag] = origin_of_[step.inputs.front()];
      if (!spec->consumes.empty()) {
        if (step.inputs.empty())
          throw fail(fmt::format("{} before any data (start the pipeline with a file to read)", spec->name == "write" ? "a writer" : "a stage"));
        if (multi && step.inputs.size() < 2)
          throw fail(fmt::format("needs at least 2 inputs, got {} (give \"inputs\": [tags])", step.inputs.size()));
        if (!multi && step.inputs.size() != spec->consumes.size())
          throw fail(fmt::format("takes {} input{}, got {}", spec->consumes.size(), spec->consumes.size() == 1 ? "" : "s",
                                       step.inputs.size()));
      }
      for (const std::string& in : step.inputs) open.erase(std::remove(open.begin(), open.end(), in), open.end());
      if (spec->produces) {
        known_.insert(step.tag);
        open.push_back(step.tag);
        last = step.tag;
      }
      p.steps.push_back(std::move(step));
    }
    if (std::none_of(p.steps.begin(), p.steps.end(), [](const PipelineStep& s) { return is_writer(s) || s.spec->measures() || !s.spec->writes_param.empty(); }))
      throw UsageError(fmt::format("{}: no output: end the pipeline with a file name to write", origin_));
    return p;
  }

private:
  void apply_overrides(std::vector<RawStep>& raw, const std::vector<std::string>& overrides) {
    for (const std::string& o : overrides) {
      const std::size_t dot = o.find('.'), eq = o.find('=');
      if (dot == std::string::npos || eq == std::string::npos || dot > eq || dot == 0 || eq == dot + 1)
        throw UsageError(fmt::format("--set \"{}\": expected STAGE.KEY=VALUE (STAGE a tag, or a type that occurs once)", o));
      const std::string stage = o.substr(0, dot), key = o.substr(dot + 1, eq - dot - 1), value = o.substr(eq + 1);
      std::vector<std::size_t> by_tag, by_type;
      std::vector<std::string> names;
      for (std::size_t i = 0; i < raw.size(); ++i) {
        const std::string tag = raw[i].has_tag ? raw[i].tag : fmt::format("{}{}", raw[i].type, i + 1);
        names.push_back(tag);
        names.push_back(raw[i].type);
        if (tag == stage) by_tag.push_back(i);
        if (raw[i].type == stage) by_type.push_back(i);
      }
      std::size_t target = 0;
      if (by_tag.size() == 1) {
        target = by_tag.front();
      } else if (by_type.size() == 1) {
        target = by_type.front();
      } else if (by_type.size() > 1) {
        std::vector<std::string> tags;  // the tags of those stages, as the user would write them
        for (const std::size_t i : by_type) tags.push_back(fmt::format("\"{}.{}={}\"", names[2 * i], key, value));
        throw UsageError(fmt::format("--set \"{}\": {} stages have type \"{}\"; name one by its tag: {}", o, by_type.size(), stage,
                                     join(tags, " or ")));
      } else {
        const std::string near = closest_name(stage, names);
        throw UsageError(fmt::format("--set \"{}\": no stage tagged or typed \"{}\"{}", o, stage,
                                     near.empty() ? "" : fmt::format("; did you mean \"{}\"?", near)));
      }
      RawValue v;
      v.kind = RawValue::Kind::Text;
      v.s = value;
      auto& params = raw[target].params;
      const auto it = std::find_if(params.begin(), params.end(), [&](const auto& kv) { return kv.first == key; });
      if (it != params.end()) it->second = v;
      else params.emplace_back(key, v);
    }
  }

  std::string origin_;
  std::set<std::string> known_;
  std::map<std::string, std::string> origin_of_;  // tag -> the reader its chain starts from
};


}  // namespace

Pipeline parse_pipeline(const std::string& json_text, const std::string& origin, const std::vector<std::string>& overrides) {
  return Builder(origin).build(detail::parse_raw_pipeline(json_text, origin), overrides);
}

Pipeline build_pipeline(const std::vector<StepText>& steps, const std::string& origin) {
  std::vector<RawStep> raw;
  for (const StepText& s : steps) {
    RawStep r;
    r.type = s.type;
    r.tag = s.tag;
    r.has_tag = !s.tag.empty();
    r.inputs = s.inputs;
    r.has_inputs = !s.inputs.empty();
    for (const auto& [key, value] : s.params) {
      RawValue v;
      v.kind = RawValue::Kind::Text;
      v.s = value;
      r.params.emplace_back(key, v);
    }
    raw.push_back(std::move(r));
  }
  return Builder(origin).build(std::move(raw), {});
}

void run_pipeline(const Pipeline& pipeline, Context& context, RunReport& report, const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  report.origin = pipeline.origin;
  report.ok = false;
  std::vector<std::filesystem::path> written;
  auto finish = [&] {
    report.total_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    report.peak_rss_mb = peak_rss_mb();
    report.tree_builds = context.tree_builds();
  };
  try {
    // Before any work: every input readable, every output writable (and distinct).
    std::vector<std::string> outputs;
    for (const PipelineStep& s : pipeline.steps) {
      const std::string& file = s.args.has("filename") ? s.args.text("filename") : std::string();
      // The error keeps the file as data (the report's error.file, Python's e.file).
      const auto checked = [](const std::string& path, auto&& check) {
        try {
          check();
        } catch (Error& e) {
          e.set_file(path);
          throw;
        }
      };
      if (is_reader(s)) checked(file, [&] { check_input_path(file); });
      const std::string& own = s.spec->writes_param.empty() ? std::string() : s.args.text(s.spec->writes_param);
      if (!own.empty()) checked(own, [&] { check_output_path(own, options.no_clobber, "own"); });
      for (const std::string& o : outputs)
        if (!own.empty() && same_path(o, own)) throw UsageError(fmt::format("{} is written twice", own), ErrorPlace{pipeline.origin});
      if (!own.empty()) outputs.push_back(own);
      if (is_writer(s)) {
        checked(file, [&] { check_output_path(file, options.no_clobber, s.args.text("format")); });
        for (const std::string& o : outputs)
          if (same_path(o, file)) throw UsageError(fmt::format("{} is written twice", file), ErrorPlace{pipeline.origin});
        outputs.push_back(file);
      }
    }
    // The last step reading each tag may take its data over instead of copying it.
    std::map<std::string, std::size_t> last_use;
    for (std::size_t i = 0; i < pipeline.steps.size(); ++i)
      for (const std::string& in : pipeline.steps[i].inputs) last_use[in] = i;

    for (std::size_t i = 0; i < pipeline.steps.size(); ++i) {
      const PipelineStep& step = pipeline.steps[i];
      StageRecord record;
      record.index = i + 1;
      record.type = step.spec->name;
      record.tag = step.tag;
      record.inputs = step.inputs;
      record.warnings = step.warnings;
      for (const auto& [key, value] : step.args.values()) {
        if (step.spec->method_list && key != "method") continue;
        record.parameters.emplace_back(key, value);
      }
      if (step.spec->method_list)
        for (const StageArgs& a : step.per_method)
          for (const auto& [key, value] : a.values())
            if (key != "method") record.parameters.emplace_back(a.method() + "." + key, value);

      std::vector<std::string> inputs = step.inputs;
      const bool in_place = step.spec->produces && step.inputs.size() == 1 && !step.spec->takes_many();
      if (in_place) {
        if (last_use[step.inputs.front()] == i) context.rename(step.inputs.front(), step.tag);
        else context.copy(step.inputs.front(), step.tag);
        inputs = {step.tag};
      }
      const double rss_before = peak_rss_mb();
      const std::size_t builds_before = context.tree_builds();
      const auto stage_start = std::chrono::steady_clock::now();
      ProgressCallback progress = options.progress ? options.progress(record) : ProgressCallback{};
      StageRun run{context, step.args, inputs, step.tag, record, progress, step.per_method};
      try {
        step.spec->run(run);
      } catch (Error& e) {
        // Name the stage and rethrow the same error (its kind, and so the exit code, kept).
        e.set_stage("", i + 1, step.spec->name);
        if (step.spec->shape == CommandShape::Read || step.spec->shape == CommandShape::Write) e.set_file(step.args.text("filename"));
        report.stages.push_back(record);
        throw;
      }
      if (progress) (void)progress(1.0);  // every stage's progress ends at 1, whatever its last report
      record.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_start).count();
      record.peak_rss_mb = peak_rss_mb();
      record.rss_rise_mb = record.peak_rss_mb - rss_before;
      record.tree_builds = context.tree_builds() - builds_before;
      if (is_writer(step)) written.emplace_back(step.args.text("filename"));
      if (!step.spec->writes_param.empty()) written.emplace_back(step.args.text(step.spec->writes_param));
      // Data no later stage reads is dropped now, not at the end.
      for (const std::string& in : step.inputs)
        if (last_use[in] == i && context.has(in) && !in_place) context.erase(in);
      for (const std::string& w : record.warnings) report.warnings.push_back(fmt::format("stage {} ({}): {}", i + 1, record.type, w));
      report.stages.push_back(record);
      if (options.stage_done) options.stage_done(report.stages.back());
    }
  } catch (const Error& e) {
    for (const auto& path : written) remove_output(path);
    report.fail(e);
    finish();
    throw;
  }
  for (const auto& path : written) report.outputs.push_back(path.string());
  report.ok = true;
  finish();
}

void RunReport::fail(const Error& e) {
  ok = false;
  error = e.what();
  error_kind = error_kind_name(e.kind());
  error_place = e.place();
  error_message = e.message();
  exit_code = e.exit_code();
}

}  // namespace pointsurf
