// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/stage.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

const char* param_type_name(ParamType type) noexcept {
  switch (type) {
    case ParamType::Bool: return "boolean";
    case ParamType::Int: return "integer";
    case ParamType::Double: return "number";
    case ParamType::String: return "string";
    case ParamType::Choice: return "choice";
    case ParamType::ChoiceList: return "list of choices";
    case ParamType::Vector3: return "3 numbers X,Y,Z";
    case ParamType::DoubleList: return "list of numbers";
  }
  return "";
}

namespace {
std::string number_text(double v) {
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return fmt::format("{}", v);
}
}  // namespace

std::string format_value(const ParamValue& value) {
  struct Visitor {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(std::int64_t i) const { return std::to_string(i); }
    std::string operator()(double d) const { return number_text(d); }
    std::string operator()(const std::string& s) const { return s; }
    std::string operator()(const std::vector<double>& v) const {
      std::string out;
      for (double d : v) out += (out.empty() ? "" : ",") + number_text(d);
      return out;
    }
  };
  return std::visit(Visitor{}, value);
}

bool ParamSpec::has_range() const noexcept { return std::isfinite(min) || std::isfinite(max); }

std::string ParamSpec::range_text() const {
  if (!has_range()) return "";
  return fmt::format("{}{}, {}{}", min_open || !std::isfinite(min) ? "(" : "[", number_text(min), number_text(max),
                     max_open || !std::isfinite(max) ? ")" : "]");
}

bool ParamSpec::applies_to(const std::string& method) const {
  return methods.empty() || std::find(methods.begin(), methods.end(), method) != methods.end();
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

const ParamSpec* StageSpec::find_param(const std::string& name) const {
  for (const ParamSpec& p : params)
    if (p.name == name) return &p;
  return nullptr;
}

std::vector<const ParamSpec*> StageSpec::params_named(const std::string& name) const {
  std::vector<const ParamSpec*> out;
  for (const ParamSpec& p : params)
    if (p.name == name) out.push_back(&p);
  return out;
}

}  // namespace pointsurf
