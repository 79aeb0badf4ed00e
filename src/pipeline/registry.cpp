// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/pipeline/registry.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "pipeline/detail/declare.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

const std::vector<StageSpec>& registered_stages() {
  static const std::vector<StageSpec> stages = [] {
    std::vector<StageSpec> s = {detail::read_stage(),      detail::write_stage(),    detail::crop_stage(),
                                detail::range_stage(),     detail::transform_stage(), detail::merge_stage(),
                                detail::clean_stage(),     detail::simplify_stage(), detail::normals_stage(),
                                detail::curvature_stage(), detail::features_stage(), detail::segment_stage(), detail::boundary_stage(), detail::reconstruct_stage(),
                                detail::quality_stage(),   detail::evaluate_stage(),    detail::render_stage(),
                                detail::register_stage(),  detail::register_many_stage()};
    std::stable_sort(s.begin(), s.end(), [](const StageSpec& a, const StageSpec& b) { return a.order < b.order; });
    return s;
  }();
  return stages;
}

const StageSpec* find_stage(std::string_view name) {
  for (const StageSpec& s : registered_stages())
    if (s.name == name) return &s;
  return nullptr;
}

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      // A swap of two neighbours counts as one edit, as users type it.
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string closest_name(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_distance = std::max<std::size_t>(1, std::min<std::size_t>(3, (word.size() + 2) / 3)) + 1;
  for (const std::string& c : candidates) {
    std::size_t d = edit_distance(word, c);
    // "nromals" for "normals": a transposition is one typo, not two.
    if (d == 2 && word.size() == c.size()) {
      std::size_t first = 0;
      while (first < c.size() && word[first] == c[first]) ++first;
      if (first + 1 < c.size() && word[first] == c[first + 1] && word[first + 1] == c[first] &&
          word.substr(first + 2) == std::string_view(c).substr(first + 2))
        d = 1;
    }
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  return best;
}

namespace {

bool parse_double(const std::string& text, double& out) {
  try {
    std::size_t used = 0;
    out = std::stod(text, &used);
    return used == text.size() && std::isfinite(out);
  } catch (const std::exception&) {
    return false;
  }
}

std::string choices_text(const std::vector<std::string>& choices) {
  std::string out;
  for (std::size_t i = 0; i < choices.size(); ++i)
    out += (i == 0 ? "" : i + 1 == choices.size() ? " or " : ", ") + choices[i];
  return out;
}

void check_number(const ParamSpec& spec, double v, const std::string& shown) {
  const bool ok = (spec.min_open ? v > spec.min : v >= spec.min) && (spec.max_open ? v < spec.max : v <= spec.max);
  if (!ok) throw UsageError(fmt::format("{}: {} is out of range {}", spec.name, shown, spec.range_text()));
}

void check_choice(const ParamSpec& spec, const std::string& value) {
  if (std::find(spec.choices.begin(), spec.choices.end(), value) != spec.choices.end()) return;
  const std::string near = closest_name(value, spec.choices);
  throw UsageError(fmt::format("{}: \"{}\" is not one of {}{}", spec.name, value, choices_text(spec.choices),
                               near.empty() ? "" : fmt::format("; did you mean \"{}\"?", near)));
}

}  // namespace

void check_param_value(const ParamSpec& spec, const ParamValue& value) {
  switch (spec.type) {
    case ParamType::Int: {
      const auto v = std::get<std::int64_t>(value);
      check_number(spec, static_cast<double>(v), std::to_string(v));
      break;
    }
    case ParamType::Double: check_number(spec, std::get<double>(value), format_value(value)); break;
    case ParamType::Choice: check_choice(spec, std::get<std::string>(value)); break;
    case ParamType::ChoiceList: {
      std::stringstream stream(std::get<std::string>(value));
      std::string item;
      std::size_t n = 0;
      while (std::getline(stream, item, ',')) {
        check_choice(spec, item);
        ++n;
      }
      if (n == 0) throw UsageError(fmt::format("{}: expected at least one of {}", spec.name, choices_text(spec.choices)));
      break;
    }
    case ParamType::Vector3:
    case ParamType::DoubleList:
      for (double v : std::get<std::vector<double>>(value)) check_number(spec, v, format_value(ParamValue(v)));
      if (spec.type == ParamType::DoubleList && std::get<std::vector<double>>(value).empty())
        throw UsageError(fmt::format("{}: expected at least one number", spec.name));
      break;
    case ParamType::Bool:
    case ParamType::String: break;
  }
}

ParamValue parse_param_text(const ParamSpec& spec, const std::string& text) {
  ParamValue value;
  switch (spec.type) {
    case ParamType::Bool: {
      std::string t = text;
      std::transform(t.begin(), t.end(), t.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (t == "true" || t == "1" || t == "yes" || t == "on") value = true;
      else if (t == "false" || t == "0" || t == "no" || t == "off") value = false;
      else throw UsageError(fmt::format("{}: \"{}\" is not a boolean (expected true or false)", spec.name, text));
      break;
    }
    case ParamType::Int: {
      double d = 0.0;
      if (!parse_double(text, d) || d != std::floor(d) || std::abs(d) > 9.0e15)
        throw UsageError(fmt::format("{}: \"{}\" is not an integer", spec.name, text));
      value = static_cast<std::int64_t>(d);
      break;
    }
    case ParamType::Double: {
      double d = 0.0;
      if (!parse_double(text, d)) throw UsageError(fmt::format("{}: \"{}\" is not a number", spec.name, text));
      value = d;
      break;
    }
    case ParamType::String:
    case ParamType::Choice:
    case ParamType::ChoiceList: value = text; break;
    case ParamType::Vector3:
    case ParamType::DoubleList: {
      std::vector<double> numbers;
      std::stringstream stream(text);
      std::string item;
      while (std::getline(stream, item, ',')) {
        double d = 0.0;
        if (!parse_double(item, d))
          throw UsageError(fmt::format("{}: \"{}\": \"{}\" is not a number (expected {})", spec.name, text, item,
                                       param_type_name(spec.type)));
        numbers.push_back(d);
      }
      if (spec.type == ParamType::Vector3 && numbers.size() != 3)
        throw UsageError(fmt::format("{}: \"{}\": expected 3 numbers X,Y,Z, got {}", spec.name, text, numbers.size()));
      value = std::move(numbers);
      break;
    }
  }
  check_param_value(spec, value);
  return value;
}

}  // namespace pointsurf
