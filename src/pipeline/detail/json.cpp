// SPDX-License-Identifier: GPL-3.0-or-later
// The only place JSON meets the pipeline: parsing a pipeline file and writing the report.
#include <cmath>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "pipeline/detail/raw_step.h"
#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/pipeline.h"

namespace pointsurf {
namespace detail {

namespace {

RawValue raw_value(const nlohmann::json& j) {
  RawValue v;
  if (j.is_boolean()) {
    v.kind = RawValue::Kind::Bool;
    v.b = j.get<bool>();
  } else if (j.is_number_integer()) {
    v.kind = RawValue::Kind::Int;
    v.i = j.get<std::int64_t>();
    v.d = static_cast<double>(v.i);
  } else if (j.is_number()) {
    v.kind = RawValue::Kind::Double;
    v.d = j.get<double>();
  } else if (j.is_string()) {
    v.kind = RawValue::Kind::String;
    v.s = j.get<std::string>();
  } else if (j.is_array() && !j.empty() && std::all_of(j.begin(), j.end(), [](const auto& e) { return e.is_number(); })) {
    v.kind = RawValue::Kind::Numbers;
    for (const auto& e : j) v.numbers.push_back(e.get<double>());
  } else if (j.is_array() && !j.empty() && std::all_of(j.begin(), j.end(), [](const auto& e) { return e.is_string(); })) {
    v.kind = RawValue::Kind::Strings;
    for (const auto& e : j) v.strings.push_back(e.get<std::string>());
  } else {
    v.kind = RawValue::Kind::Other;
    v.s = j.is_array() ? (j.empty() ? "an empty list" : "a mixed list") : j.is_object() ? "an object" : j.is_null() ? "null" : "a value";
  }
  return v;
}

}  // namespace

std::vector<RawStep> parse_raw_pipeline(const std::string& text, const std::string& origin) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the offset where parsing failed: give the line and column.
    std::size_t line = 1, column = 1;
    for (std::size_t i = 0; i + 1 < e.byte && i < text.size(); ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
    ErrorPlace at;
    at.origin = origin;
    at.offset = fmt::format("line {}, column {}", line, column);
    throw UsageError(fmt::format("not valid JSON at {}", at.offset), at);
  }
  // PDAL also accepts {"pipeline": [...]}.
  if (j.is_object() && j.contains("pipeline")) j = j["pipeline"];
  if (!j.is_array()) throw UsageError("a pipeline is a JSON list of stages (file names and objects)", ErrorPlace{origin});
  if (j.empty()) throw UsageError("the pipeline is empty", ErrorPlace{origin});
  std::vector<RawStep> steps;
  for (std::size_t i = 0; i < j.size(); ++i) {
    const nlohmann::json& e = j[i];
    RawStep step;
    if (e.is_string()) {
      step.is_file = true;
      step.file = e.get<std::string>();
      steps.push_back(std::move(step));
      continue;
    }
    if (!e.is_object()) throw UsageError(fmt::format("stage {}: expected a file name or an object with \"type\"", i + 1), ErrorPlace{origin});
    if (!e.contains("type") || !e["type"].is_string())
      throw UsageError(fmt::format("stage {}: missing \"type\" (a string naming the stage)", i + 1), ErrorPlace{origin});
    step.type = e["type"].get<std::string>();
    for (auto it = e.begin(); it != e.end(); ++it) {
      const std::string& key = it.key();
      if (key == "type") continue;
      if (key == "tag") {
        if (!it->is_string() || it->get<std::string>().empty())
          throw UsageError("\"tag\" must be a non-empty string", ErrorPlace{origin, i + 1, step.type});
        step.tag = it->get<std::string>();
        step.has_tag = true;
      } else if (key == "inputs") {
        step.has_inputs = true;
        if (it->is_string()) {
          step.inputs.push_back(it->get<std::string>());
        } else if (it->is_array() && std::all_of(it->begin(), it->end(), [](const auto& x) { return x.is_string(); })) {
          for (const auto& x : *it) step.inputs.push_back(x.get<std::string>());
        } else {
          throw UsageError("\"inputs\" must be a tag or a list of tags", ErrorPlace{origin, i + 1, step.type});
        }
      } else {
        step.params.emplace_back(key, raw_value(*it));
      }
    }
    steps.push_back(std::move(step));
  }
  return steps;
}

namespace {

nlohmann::json to_json(const ParamValue& v) {
  return std::visit(
      [](const auto& x) -> nlohmann::json {
        using T = std::decay_t<decltype(x)>;
        // A length in cloud units is a number, one in spacings the text "3sp" (as written).
        if constexpr (std::is_same_v<T, Length>) return x.in_spacings() ? nlohmann::json(x.text()) : nlohmann::json(x.value);
        else return nlohmann::json(x);
      },
      v);
}

nlohmann::json to_json(const ResultValue& v) {
  return std::visit(
      [](const auto& x) -> nlohmann::json {
        using T = std::decay_t<decltype(x)>;
        if constexpr (std::is_same_v<T, double>) {
          if (!std::isfinite(x)) return nullptr;
        }
        return nlohmann::json(x);
      },
      v);
}

nlohmann::json to_json(const ResultList& list) {
  nlohmann::json out = nlohmann::json::object();
  // A key with '/' nests: "deviation/rms" is {"deviation": {"rms": ...}}.
  for (const auto& [key, value] : list) {
    if (key.find('/') == std::string::npos) out[key] = to_json(value);
    else out[nlohmann::json::json_pointer("/" + key)] = to_json(value);
  }
  return out;
}

}  // namespace
}  // namespace detail

std::string report_json(const RunReport& report) {
  using nlohmann::json;
  json stages = json::array();
  for (const StageRecord& r : report.stages) {
    json parameters = json::object();
    for (const auto& [key, value] : r.parameters) parameters[key] = detail::to_json(value);
    stages.push_back({{"index", r.index},
                      {"type", r.type},
                      {"tag", r.tag},
                      {"inputs", r.inputs},
                      {"parameters", parameters},
                      {"counts", detail::to_json(r.counts)},
                      {"metrics", detail::to_json(r.metrics)},
                      {"warnings", r.warnings},
                      {"seconds", r.seconds},
                      {"peak_rss_mb", r.peak_rss_mb},
                      {"rss_rise_mb", r.rss_rise_mb},
                      {"kdtree_builds", r.tree_builds}});
  }
  json out = {{"command", report.command},
              {"version", POINTSURF_VERSION},
              {"pipeline", report.origin},
              {"status", report.ok ? "ok" : report.error_kind == "cancelled" ? "cancelled" : "failed"},
              {"stages", stages},
              {"outputs", report.outputs},
              {"warnings", report.warnings},
              {"kdtree_builds", report.tree_builds},
              {"total_seconds", report.total_seconds},
              {"peak_rss_mb", report.peak_rss_mb}};
  if (!report.ok) {
    json error = {{"message", report.error}, {"exit_code", report.exit_code}};
    // The error as data (core/error.h): its kind and, where known, the stage, key, file and place.
    if (!report.error_kind.empty()) error["kind"] = report.error_kind;
    const ErrorPlace& at = report.error_place;
    if (at.stage_index > 0) {
      error["stage_index"] = at.stage_index;
      error["stage"] = at.stage;
    }
    if (!at.key.empty()) error["key"] = at.key;
    if (!at.file.empty()) error["file"] = at.file;
    if (!at.offset.empty()) error["offset"] = at.offset;
    if (!report.error_message.empty()) error["text"] = report.error_message;
    out["error"] = std::move(error);
  }
  return out.dump(2) + "\n";
}

}  // namespace pointsurf
