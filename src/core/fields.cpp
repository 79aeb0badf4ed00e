// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/fields.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <sstream>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

std::string Length::text() const {
  const std::string number = std::isinf(value) ? (value > 0 ? "inf" : "-inf") : fmt::format("{}", value);
  return unit == Unit::Spacings ? number + "sp" : number;
}

Length Length::parse(std::string_view text, std::string_view key) {
  std::string t(text);
  while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
  Unit unit = Unit::Cloud;
  for (const char* suffix : {"spacings", "spacing", "sp"}) {
    const std::string_view s(suffix);
    if (t.size() > s.size() && t.compare(t.size() - s.size(), s.size(), s) == 0) {
      t.resize(t.size() - s.size());
      while (!t.empty() && std::isspace(static_cast<unsigned char>(t.back()))) t.pop_back();
      unit = Unit::Spacings;
      break;
    }
  }
  double v = 0.0;
  std::size_t used = 0;
  bool ok = !t.empty();
  if (ok) {
    try {
      v = std::stod(t, &used);
    } catch (const std::exception&) {
      ok = false;
    }
  }
  if (!ok || used != t.size() || !std::isfinite(v))
    throw key_error(key, fmt::format("\"{}\" is not a length (expected a number in cloud units, or in mean spacings as \"3sp\")", text));
  return {v, unit};
}

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
    case ParamType::Length: return "length";
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
    std::string operator()(const Length& l) const { return l.text(); }
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
  // A declared range is finite: inf and NaN are refused as the library's checks always did.
  const bool ok = (!spec.has_range() || std::isfinite(v)) && (spec.min_open ? v > spec.min : v >= spec.min) &&
                  (spec.max_open ? v < spec.max : v <= spec.max);
  if (!ok) throw key_error(spec.name, fmt::format("{} is out of range {}", shown, spec.range_text()));
}

void check_choice(const ParamSpec& spec, const std::string& value) {
  if (std::find(spec.choices.begin(), spec.choices.end(), value) != spec.choices.end()) return;
  const std::string near = closest_name(value, spec.choices);
  throw key_error(spec.name, fmt::format("\"{}\" is not one of {}{}", value, choices_text(spec.choices),
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
      if (n == 0) throw key_error(spec.name, fmt::format("expected at least one of {}", choices_text(spec.choices)));
      break;
    }
    case ParamType::Vector3:
    case ParamType::DoubleList:
      for (double v : std::get<std::vector<double>>(value)) check_number(spec, v, format_value(ParamValue(v)));
      if (spec.type == ParamType::DoubleList && std::get<std::vector<double>>(value).empty())
        throw key_error(spec.name, "expected at least one number");
      break;
    case ParamType::Length: {
      const Length& l = std::get<Length>(value);
      check_number(spec, l.value, l.text());
      break;
    }
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
      else throw key_error(spec.name, fmt::format("\"{}\" is not a boolean (expected true or false)", text));
      break;
    }
    case ParamType::Int: {
      double d = 0.0;
      if (!parse_double(text, d) || d != std::floor(d) || std::abs(d) > 9.0e15)
        throw key_error(spec.name, fmt::format("\"{}\" is not an integer", text));
      value = static_cast<std::int64_t>(d);
      break;
    }
    case ParamType::Double: {
      double d = 0.0;
      if (!parse_double(text, d)) throw key_error(spec.name, fmt::format("\"{}\" is not a number", text));
      value = d;
      break;
    }
    case ParamType::String:
    case ParamType::Choice:
    case ParamType::ChoiceList: value = text; break;
    case ParamType::Length: value = Length::parse(text, spec.name); break;
    case ParamType::Vector3:
    case ParamType::DoubleList: {
      std::vector<double> numbers;
      std::stringstream stream(text);
      std::string item;
      while (std::getline(stream, item, ',')) {
        double d = 0.0;
        if (!parse_double(item, d))
          throw key_error(spec.name, fmt::format("\"{}\": \"{}\" is not a number (expected {})", text, item,
                                       param_type_name(spec.type)));
        numbers.push_back(d);
      }
      if (spec.type == ParamType::Vector3 && numbers.size() != 3)
        throw key_error(spec.name, fmt::format("\"{}\": expected 3 numbers X,Y,Z, got {}", text, numbers.size()));
      value = std::move(numbers);
      break;
    }
  }
  check_param_value(spec, value);
  return value;
}


namespace {
std::string bound_text(double v) { return fmt::format("{}", v); }
}  // namespace

std::string range_failure(const ParamSpec& spec, const ParamValue& value) {
  try {
    check_param_value(spec, value);
    return {};
  } catch (const UsageError&) {
  }
  // The library's wording: "k must be >= 3, got 2", "ratio must be in (0, 1], got 1.5".
  std::string got;
  if (const auto* l = std::get_if<Length>(&value)) got = l->text();
  else got = format_value(value);
  if (spec.type == ParamType::Choice || spec.type == ParamType::ChoiceList) {
    std::string list;
    for (std::size_t i = 0; i < spec.choices.size(); ++i) list += (i == 0 ? "" : ", ") + spec.choices[i];
    return fmt::format("{} must be one of {}, got \"{}\"", spec.name, list, got);
  }
  const bool lo = std::isfinite(spec.min), hi = std::isfinite(spec.max);
  std::string rule;
  if (lo && hi) rule = fmt::format("in {}", spec.range_text());
  else if (lo) rule = fmt::format("{} {}", spec.min_open ? ">" : ">=", bound_text(spec.min));
  else if (hi) rule = fmt::format("{} {}", spec.max_open ? "<" : "<=", bound_text(spec.max));
  else rule = "finite";
  if (spec.type == ParamType::DoubleList && std::get<std::vector<double>>(value).empty())
    return fmt::format("{} must hold at least one number", spec.name);
  return fmt::format("{} must be {}, got {}", spec.name, rule, got);
}

namespace detail {
void throw_field_usage(std::string_view function, const std::string& failure, const std::string& key) {
  ErrorPlace place;
  place.key = key;
  throw UsageError(function.empty() ? failure : fmt::format("{}: {}", function, failure), std::move(place));
}
}  // namespace detail

}  // namespace pointsurf
