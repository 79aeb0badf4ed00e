// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/stage.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

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
