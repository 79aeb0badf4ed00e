// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Result tables: a Result struct of the library declares its reported members once, next to the
// struct (key, member or accessor, unit, which way is better, one-line doc), as Params structs
// declare their fields (core/fields.h). The pipeline's records (the report's counts and
// metrics), the report schema in docs/stages.md and the registry that Python reads come from the
// table, so a key is typed once.
//
//   struct FitResult {
//     std::size_t inliers = 0;
//     double rms = 0.0;
//     static const ResultTable<FitResult>& results();
//   };
//   const ResultTable<FitResult>& FitResult::results() {
//     static const ResultTable<FitResult> t = [] {
//       ResultTable<FitResult> t;
//       t.count("inliers", &FitResult::inliers, "Points within the band").higher_is_better().as_count();
//       t.number("rms", &FitResult::rms, "Root mean square distance").with_unit("cloud units").lower_is_better();
//       return t;
//     }();
//     return t;
//   }
//
// A stage's report has two blocks, "counts" (how many points, faces, segments it read and made)
// and "metrics" (everything else). A table marks its counts itself (`as_count()`; every other
// value is a metric, integers included), and a nested table's values keep their own blocks.
// A stage records a table with StageRecord::add, which puts each value in the block its spec
// says, and declares the same in StageSpec::results, one list whose specs carry their block:
//
//   run.record.add(FitResult::results(), fit, "fit/");                    // counts "fit/inliers", metrics "fit/rms"
//   s.results = prefixed(FitResult::results().specs(), "fit/");            // the same, declared
//
// A small table of the stage's own (values that belong to no library struct) may leave its
// blocks unmarked and be recorded with StageRecord::add_counts and declared with counted(...),
// which make every value of it a count.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace pointsurf {

/// One reported value: an integer (counts), a number, a text, a flag or a list of numbers.
using ResultValue = std::variant<std::int64_t, double, std::string, bool, std::vector<double>>;
/// Reported values in the order they were recorded.
using ResultList = std::vector<std::pair<std::string, ResultValue>>;

/// Which way a reported value is better, for the report's colours and comparisons.
enum class Better { Neither, Higher, Lower };
const char* better_name(Better b) noexcept;  // "", "higher", "lower"

/// The type of a reported value, as docs/stages.md and Python show it.
enum class ResultType { Integer, Number, Text, Flag, Numbers };
const char* result_type_name(ResultType t) noexcept;  // "integer", "number", "text", "flag", "numbers"

/// The block of a stage's report a value is recorded in.
enum class ResultBlock { Metrics, Counts };
const char* result_block_name(ResultBlock b) noexcept;  // "metrics", "counts"

/// What a reported value is, without the struct it comes from.
struct ResultSpec {
  std::string key;                   // "rms"; with its block's prefix in a stage ("deviation/rms").
                                     // A key ending in "*" is a family (one key per rank or
                                     // region, e.g. "percentiles/p*")
  ResultType type = ResultType::Number;
  std::string unit;                  // "cloud units", "degrees", "" (none)
  Better better = Better::Neither;
  std::string doc;                   // one line
  ResultBlock block = ResultBlock::Metrics;  // as_count() in the table, or counted() in a
                                             // stage's declaration, makes it a count
  bool headline = false;             // one of the few values a summary shows (the HTML report's
                                     // deviation table)

  ResultSpec& with_unit(std::string u) { unit = std::move(u); return *this; }
  ResultSpec& higher_is_better() { better = Better::Higher; return *this; }
  ResultSpec& lower_is_better() { better = Better::Lower; return *this; }
  ResultSpec& in_headline() { headline = true; return *this; }
  /// Reported in the block "counts" of a stage's report (the default is "metrics").
  ResultSpec& as_count() { block = ResultBlock::Counts; return *this; }
};

/// The specs of `specs` with `prefix` in front of each key (a block of a stage's report).
std::vector<ResultSpec> prefixed(std::vector<ResultSpec> specs, const std::string& prefix);
/// The specs of `specs` as counts of a stage's report, `prefix` in front of each key.
std::vector<ResultSpec> counted(std::vector<ResultSpec> specs, const std::string& prefix = "");
/// Appends `more` to `specs` (a stage's declaration built from several tables).
void append(std::vector<ResultSpec>& specs, const std::vector<ResultSpec>& more);

/// The reported members of a Result struct R, in report order.
template <class R>
class ResultTable {
public:
  using Emit = std::function<void(std::string key, ResultValue value)>;
  /// The same, told the block of each value (its spec's).
  using BlockEmit = std::function<void(ResultBlock block, std::string key, ResultValue value)>;

  /// A count (any integer member), reported as an integer.
  template <class I>
  ResultSpec& count(std::string key, I R::*member, std::string doc) {
    static_assert(std::is_integral_v<I>);
    return add(std::move(key), ResultType::Integer, std::move(doc),
               [member](const R& r, const std::string& k, const Emit& emit) { emit(k, static_cast<std::int64_t>(r.*member)); });
  }
  ResultSpec& number(std::string key, double R::*member, std::string doc) {
    return add(std::move(key), ResultType::Number, std::move(doc), [member](const R& r, const std::string& k, const Emit& emit) { emit(k, r.*member); });
  }
  ResultSpec& flag(std::string key, bool R::*member, std::string doc) {
    return add(std::move(key), ResultType::Flag, std::move(doc), [member](const R& r, const std::string& k, const Emit& emit) { emit(k, r.*member); });
  }
  ResultSpec& text(std::string key, std::string R::*member, std::string doc) {
    return add(std::move(key), ResultType::Text, std::move(doc), [member](const R& r, const std::string& k, const Emit& emit) { emit(k, r.*member); });
  }
  /// A list of numbers (doubles or counts).
  template <class T>
  ResultSpec& numbers(std::string key, std::vector<T> R::*member, std::string doc) {
    return add(std::move(key), ResultType::Numbers, std::move(doc), [member](const R& r, const std::string& k, const Emit& emit) {
      const std::vector<T>& v = r.*member;
      emit(k, std::vector<double>(v.begin(), v.end()));
    });
  }
  /// A value computed from the struct (a count of a list, a value that may be undefined).
  ResultSpec& computed(std::string key, ResultType type, std::function<ResultValue(const R&)> get, std::string doc) {
    return add(std::move(key), type, std::move(doc),
               [get = std::move(get)](const R& r, const std::string& k, const Emit& emit) { emit(k, get(r)); });
  }
  /// A family of values, one key each (`key` ends in "*": "percentiles/p*"); `get` gives the
  /// suffixes that replace "*" and the values.
  ResultSpec& family(std::string key, ResultType type, std::function<std::vector<std::pair<std::string, ResultValue>>(const R&)> get,
                     std::string doc) {
    return add(std::move(key), type, std::move(doc), [get = std::move(get)](const R& r, const std::string& k, const Emit& emit) {
      const std::string stem = k.substr(0, k.size() - 1);
      for (auto& [suffix, value] : get(r)) emit(stem + suffix, std::move(value));
    });
  }
  /// The members of a nested struct S under `prefix` ("angles_deg/").
  template <class S>
  void nested(const std::string& prefix, S R::*member, const ResultTable<S>& table) {
    const ResultTable<S>* t = &table;  // tables are function-local statics
    blocks_.push_back(Block{specs_.size(), table.specs().size(), [member, t, prefix](const R& r, const std::string& outer, const BlockEmit& emit) {
                              t->record_blocks(r.*member, emit, outer + prefix);
                            }});
    for (const ResultSpec& s : table.specs()) {
      ResultSpec copy = s;
      copy.key = prefix + s.key;
      specs_.push_back(std::move(copy));
    }
  }

  /// Emits every member of `r`, keys prefixed by `prefix`, in declaration order, each with its
  /// block (a nested table's values with theirs).
  void record_blocks(const R& r, const BlockEmit& emit, const std::string& prefix = "") const {
    std::size_t block = 0;
    for (std::size_t i = 0; i < specs_.size();) {
      if (block < blocks_.size() && blocks_[block].first == i) {
        blocks_[block].emit(r, prefix, emit);
        i += blocks_[block].size;
        ++block;
        continue;
      }
      const ResultBlock b = specs_[i].block;
      emitters_[index_[i]](r, prefix + specs_[i].key, [&emit, b](std::string key, ResultValue value) { emit(b, std::move(key), std::move(value)); });
      ++i;
    }
  }
  /// The same without the blocks.
  void record(const R& r, const Emit& emit, const std::string& prefix = "") const {
    record_blocks(r, [&emit](ResultBlock, std::string key, ResultValue value) { emit(std::move(key), std::move(value)); }, prefix);
  }

  const std::vector<ResultSpec>& specs() const noexcept { return specs_; }

private:
  using Emitter = std::function<void(const R&, const std::string& key, const Emit&)>;
  struct Block {
    std::size_t first, size;
    std::function<void(const R&, const std::string& prefix, const BlockEmit&)> emit;
  };
  ResultSpec& add(std::string key, ResultType type, std::string doc, Emitter e) {
    ResultSpec s;
    s.key = std::move(key);
    s.type = type;
    s.doc = std::move(doc);
    index_.resize(specs_.size() + 1);
    index_[specs_.size()] = emitters_.size();
    emitters_.push_back(std::move(e));
    specs_.push_back(std::move(s));
    return specs_.back();
  }
  std::vector<ResultSpec> specs_;
  std::vector<std::size_t> index_;  // spec -> emitter (specs of nested blocks have none)
  std::vector<Emitter> emitters_;
  std::vector<Block> blocks_;
};

}  // namespace pointsurf
