// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A pipeline step as written, before it is checked against the registry: from JSON (typed
// values) or from the command line (text).
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace pointsurf::detail {

struct RawValue {
  enum class Kind { Text, Bool, Int, Double, String, Numbers, Strings, Other } kind = Kind::Text;
  bool b = false;
  std::int64_t i = 0;
  double d = 0.0;
  std::string s;                    // Text, String; Other: the JSON type name
  std::vector<double> numbers;      // Numbers (a JSON array of numbers)
  std::vector<std::string> strings; // Strings (a JSON array of strings)
};

struct RawStep {
  bool is_file = false;             // a bare file name: reader or writer by position
  std::string file;
  std::string type, tag;
  bool has_tag = false;
  std::vector<std::string> inputs;
  bool has_inputs = false;
  std::vector<std::pair<std::string, RawValue>> params;
};

/// Parses the JSON text of a pipeline into raw steps; throws UsageError "ORIGIN: ..." for text
/// that is not JSON, not a list, or holds a step that is neither a string nor an object.
std::vector<RawStep> parse_raw_pipeline(const std::string& text, const std::string& origin);

}  // namespace pointsurf::detail
