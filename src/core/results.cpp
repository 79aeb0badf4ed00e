// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/results.h"

namespace pointsurf {

const char* better_name(Better b) noexcept {
  switch (b) {
    case Better::Neither: return "";
    case Better::Higher: return "higher";
    case Better::Lower: return "lower";
  }
  return "";
}

const char* result_type_name(ResultType t) noexcept {
  switch (t) {
    case ResultType::Integer: return "integer";
    case ResultType::Number: return "number";
    case ResultType::Text: return "text";
    case ResultType::Flag: return "flag";
    case ResultType::Numbers: return "numbers";
  }
  return "number";
}

const char* result_block_name(ResultBlock b) noexcept { return b == ResultBlock::Counts ? "counts" : "metrics"; }

std::vector<ResultSpec> prefixed(std::vector<ResultSpec> specs, const std::string& prefix) {
  for (ResultSpec& s : specs) s.key = prefix + s.key;
  return specs;
}

std::vector<ResultSpec> counted(std::vector<ResultSpec> specs, const std::string& prefix) {
  for (ResultSpec& s : specs) {
    s.key = prefix + s.key;
    s.block = ResultBlock::Counts;
  }
  return specs;
}

void append(std::vector<ResultSpec>& specs, const std::vector<ResultSpec>& more) { specs.insert(specs.end(), more.begin(), more.end()); }

}  // namespace pointsurf
