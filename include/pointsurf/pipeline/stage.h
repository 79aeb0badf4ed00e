// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A stage as the pipeline, the command line, the report and the bindings see it: its name, what
// it consumes and produces, its parameters (name, type, default, unit, range or choices, one-line
// doc, the methods they belong to) and a run function over a Context. Declared once, in the
// registry (pointsurf/pipeline/registry.h); every front end is generated from the declaration.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"

namespace pointsurf {

class Context;

/// What a stage reads or writes.
enum class DataKind { Cloud, Mesh, Any };

struct Slot {
  std::string name;  // "cloud", "mesh", "reference", "source", "target"
  DataKind kind = DataKind::Cloud;
};

/// What one stage did: the values it used, its counts, metrics, warnings, time and memory.
struct StageRecord {
  std::size_t index = 0;             // position in the pipeline, 1-based
  std::string type, tag;
  std::vector<std::string> inputs;   // tags of the data it read
  std::vector<std::pair<std::string, ParamValue>> parameters;  // every value used, resolved
  ResultList counts, metrics;
  std::vector<std::string> warnings;
  std::string summary;               // one line for stderr
  double seconds = 0.0;
  double peak_rss_mb = 0.0;          // high-water resident memory at the end of the stage
  double rss_rise_mb = 0.0;          // peak_rss_mb minus the high-water mark at its start
  std::size_t tree_builds = 0;       // kd-trees built during the stage

  /// Replaces the recorded value of a parameter by the one actually used (a derived default).
  void set_used(const std::string& name, ParamValue value);
  void count(std::string name, std::int64_t value) { counts.emplace_back(std::move(name), value); }
  void metric(std::string name, ResultValue value) { metrics.emplace_back(std::move(name), std::move(value)); }
  /// Records every member of `r` that its table declares under `prefix`, each in the block its
  /// spec says (as_count(): counts; else metrics).
  template <class R>
  void add(const ResultTable<R>& table, const R& r, const std::string& prefix = "") {
    table.record_blocks(r, [this](ResultBlock block, std::string key, ResultValue value) {
      (block == ResultBlock::Counts ? counts : metrics).emplace_back(std::move(key), std::move(value));
    }, prefix);
  }
  /// The same, every value as a count (a stage's own table; it declares them with counted()).
  template <class R>
  void add_counts(const ResultTable<R>& table, const R& r, const std::string& prefix = "") {
    table.record(r, [this](std::string key, ResultValue value) { counts.emplace_back(std::move(key), std::move(value)); }, prefix);
  }
};

/// The parameters of one stage run, resolved: every parameter of the chosen method, given or
/// default.
class StageArgs {
public:
  StageArgs() = default;
  StageArgs(std::map<std::string, ParamValue> values, std::map<std::string, bool> given, std::string method)
      : values_(std::move(values)), given_(std::move(given)), method_(std::move(method)) {}
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  bool given(const std::string& name) const;  // set explicitly (not a default)
  bool boolean(const std::string& name) const;
  std::int64_t integer(const std::string& name) const;
  int int32(const std::string& name) const { return static_cast<int>(integer(name)); }
  double number(const std::string& name) const;
  const std::string& text(const std::string& name) const;
  const std::vector<double>& numbers(const std::string& name) const;
  const Length& length(const std::string& name) const;
  /// The value of `name` whatever its type.
  const ParamValue& value(const std::string& name) const { return at(name); }
  const std::string& method() const noexcept { return method_; }
  const std::map<std::string, ParamValue>& values() const noexcept { return values_; }

private:
  const ParamValue& at(const std::string& name) const;
  std::map<std::string, ParamValue> values_;
  std::map<std::string, bool> given_;
  std::string method_;
};

/// A running stage's view of the context: its resolved parameters, the tags of its inputs and
/// output, its record and a progress callback (already labelled by the runner).
struct StageRun {
  Context& context;
  const StageArgs& args;
  std::vector<std::string> inputs;   // tags, one per consumed slot (several for merge)
  std::string output;                // tag the result goes under
  StageRecord& record;
  ProgressCallback progress;
  /// For stages whose "method" is a list (clean): the parameters resolved for each listed
  /// method alone, in order; otherwise one entry equal to `args`.
  const std::vector<StageArgs>& per_method;
};

/// How a stage takes its data on the command line and in Python; declared with the stage, and
/// the front ends follow it (apps/pointsurf/cmd_stage.cpp, python/pointsurf/__init__.py).
enum class CommandShape {
  Read,       // a pipeline's reader: no command of its own (pointsurf convert reads)
  Write,      // a pipeline's writer: no command of its own
  Transform,  // STAGE IN OUT: one cloud or mesh in, one out
  Merge,      // STAGE IN1 IN2 [IN...] OUT, or --out OUT: several in (slot "clouds"), one out
  Pair,       // STAGE SOURCE TARGET [--OWN FILE] [--apply OUT]: two inputs of equal standing,
              // the stage's own file (writes_param) and its product
  Compare,    // STAGE IN --reference FILE [--out FILE]: a measure of IN against a reference
  Measure,    // STAGE IN [--out FILE]: a measure of one input
  Picture,    // STAGE IN OUT: OUT is the stage's own file (writes_param), e.g. render's PNG
};

/// "transform", "merge", ... (the Python description and docs/stages.md).
const char* command_shape_name(CommandShape shape) noexcept;

struct StageSpec {
  std::string name;                  // "normals", "clean", ...
  std::string summary;               // one line for the command list
  std::string description;           // a paragraph for --help
  std::vector<Slot> consumes;        // empty: a reader; a slot with name "clouds": any number
  std::optional<Slot> produces;      // empty: produces nothing (an evaluation, a writer)
  std::vector<std::string> methods;  // empty: no "method" parameter
  std::string default_method;
  bool method_list = false;          // "method" takes a comma-separated list applied in order
  std::vector<ParamSpec> params;     // "method" is implied by `methods`
  std::vector<std::string> examples; // command lines for --help
  int order = 0;                     // place in the command list (data flow)
  /// How the command line and Python take its data (the registry checks that it agrees with
  /// consumes and produces).
  CommandShape shape = CommandShape::Transform;
  /// A stage that writes a file of its own kind (render: a PNG; register: T.json): the parameter
  /// naming it. The file is checked and cleaned up like a writer's and a pipeline may end with
  /// the stage.
  std::string writes_param;
  /// The counts and metrics its report holds (ResultSpec::block tells them apart), declared by
  /// the library's Result tables or small tables of the stage's own (core/results.h), with
  /// their prefixes ("deviation/rms"): docs/stages.md and Python show them, and a test runs
  /// every stage and checks that it records exactly these, with these types. Keys recorded
  /// only by some methods or options are declared too (the test checks them over its runs).
  std::vector<ResultSpec> results;
  std::function<void(StageRun&)> run;
  /// Checks across parameters made before any work (e.g. a viewpoint given without
  /// orient = viewpoint); throws UsageError. May be empty.
  std::function<void(const StageArgs&)> check;

  /// An evaluation (Compare, Measure): its report is its product, so a pipeline that ends with
  /// it needs no writer. A Compare's second slot, "reference", defaults to the cloud as read at
  /// the start of the first input's chain, or to the tag given by its "reference" parameter.
  bool measures() const noexcept { return shape == CommandShape::Compare || shape == CommandShape::Measure; }
  /// Takes any number of inputs (Merge: the slot "clouds").
  bool takes_many() const noexcept { return shape == CommandShape::Merge; }

  const ParamSpec* find_param(const std::string& name) const;          // any method
  std::vector<const ParamSpec*> params_named(const std::string& name) const;
  /// The parameters that name `old_key` among their former keys.
  std::vector<const ParamSpec*> params_formerly(const std::string& old_key) const;
};

/// The stage's command line, from its shape (`pointsurf normals IN OUT [options]`; a Merge gives
/// its two forms on two lines, the second starting "   or: "). Empty for Read and Write, which
/// have no command of their own. `pointsurf STAGE --help` and docs/stages.md show it.
std::string command_synopsis(const StageSpec& s);

}  // namespace pointsurf
