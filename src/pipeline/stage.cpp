// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/stage.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

const char* command_shape_name(CommandShape shape) noexcept {
  switch (shape) {
    case CommandShape::Read: return "read";
    case CommandShape::Write: return "write";
    case CommandShape::Transform: return "transform";
    case CommandShape::Merge: return "merge";
    case CommandShape::Pair: return "pair";
    case CommandShape::Compare: return "compare";
    case CommandShape::Measure: return "measure";
    case CommandShape::Picture: return "picture";
  }
  return "transform";
}

namespace {
std::string upper(std::string t) {
  for (char& c : t) c = char(std::toupper(static_cast<unsigned char>(c)));
  return t;
}
std::string dashed_option(std::string key) {
  for (char& c : key)
    if (c == '_') c = '-';
  return "--" + key;
}
}  // namespace

std::string command_synopsis(const StageSpec& s) {
  switch (s.shape) {
    case CommandShape::Read:
    case CommandShape::Write: return {};
    case CommandShape::Transform:
    case CommandShape::Picture: return fmt::format("pointsurf {} IN OUT [options]", s.name);
    case CommandShape::Merge:
      return fmt::format("pointsurf {0} IN1 IN2 [IN...] OUT [options]\n   or: pointsurf {0} IN1 IN2 [IN...] --out OUT [options]", s.name);
    case CommandShape::Pair: {
      const ParamSpec* own = s.writes_param.empty() ? nullptr : s.find_param(s.writes_param);
      const std::string file = own == nullptr ? std::string() : fmt::format(" [{} {}]", dashed_option(own->name), own->meta.empty() ? "FILE" : own->meta);
      return fmt::format("pointsurf {} {} {}{} [--apply OUT] [options]", s.name, upper(s.consumes.at(0).name), upper(s.consumes.at(1).name), file);
    }
    case CommandShape::Compare: return fmt::format("pointsurf {} IN --reference FILE [--out FILE] [options]", s.name);
    case CommandShape::Measure: return fmt::format("pointsurf {} IN [--out FILE] [options]", s.name);
  }
  return {};
}

void StageRecord::set_used(const std::string& name, ParamValue value) {
  for (auto& [key, v] : parameters)
    if (key == name) {
      v = std::move(value);
      return;
    }
  parameters.emplace_back(name, std::move(value));
}

bool StageArgs::given(const std::string& name) const {
  const auto it = given_.find(name);
  return it != given_.end() && it->second;
}

const ParamValue& StageArgs::at(const std::string& name) const {
  const auto it = values_.find(name);
  // A stage asking for a parameter it did not declare (or of another method) is a bug.
  if (it == values_.end()) throw ComputeError(fmt::format("internal: parameter \"{}\" is not set for method \"{}\"", name, method_));
  return it->second;
}

bool StageArgs::boolean(const std::string& name) const { return std::get<bool>(at(name)); }
std::int64_t StageArgs::integer(const std::string& name) const { return std::get<std::int64_t>(at(name)); }
double StageArgs::number(const std::string& name) const { return std::get<double>(at(name)); }
const std::string& StageArgs::text(const std::string& name) const { return std::get<std::string>(at(name)); }
const std::vector<double>& StageArgs::numbers(const std::string& name) const { return std::get<std::vector<double>>(at(name)); }
const Length& StageArgs::length(const std::string& name) const { return std::get<Length>(at(name)); }

const ParamSpec* StageSpec::find_param(const std::string& name) const {
  for (const ParamSpec& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

std::vector<const ParamSpec*> StageSpec::params_formerly(const std::string& old_key) const {
  std::vector<const ParamSpec*> out;
  for (const ParamSpec& p : params)
    if (std::find(p.old_names.begin(), p.old_names.end(), old_key) != p.old_names.end()) out.push_back(&p);
  return out;
}

std::vector<const ParamSpec*> StageSpec::params_named(const std::string& name) const {
  std::vector<const ParamSpec*> out;
  for (const ParamSpec& p : params)
    if (p.name == name) out.push_back(&p);
  return out;
}

}  // namespace pointsurf
