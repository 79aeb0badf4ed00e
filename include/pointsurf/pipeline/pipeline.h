// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Pipelines in PDAL's manner: a JSON list of stages, each an object with "type" and the
// stage's parameter keys, file names standing for readers (at the start) and writers (after a
// stage):
//   ["scan.las", {"type": "clean", "method": "sor"}, {"type": "normals", "k": 20},
//    {"type": "reconstruct", "method": "ball-pivot"}, "mesh.ply"]
// A stage may carry "tag" (the name its output goes under; default "<type><index>") and
// "inputs" (tags it reads; default the previous stage's output). Everything is checked before
// any work: the JSON, stage types, keys ("did you mean"), value types, ranges and choices,
// parameters of another method, inputs, writers before any data, output paths.
#include <cstddef>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pointsurf/core/error.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/pipeline/stage.h"

namespace pointsurf {

/// One checked step: its stage, tag, inputs and resolved parameters.
struct PipelineStep {
  const StageSpec* spec = nullptr;
  std::string tag;
  std::vector<std::string> inputs;
  StageArgs args;
  std::vector<StageArgs> per_method;  // a method list (clean): each method's own; else {args}
  std::vector<std::string> warnings;  // found while checking (a deprecated key), added to the record
};

struct Pipeline {
  std::string origin;              // file name (or command) errors are prefixed with
  std::vector<PipelineStep> steps;
};

/// A step given as text, the command line's form: values are parsed as by --set.
struct StepText {
  std::string type, tag;
  std::vector<std::string> inputs;
  std::vector<std::pair<std::string, std::string>> params;
};

/// Parses and checks a JSON pipeline, then applies the `overrides` ("STAGE.KEY=VALUE", STAGE a
/// tag or a type that occurs once). Throws UsageError "ORIGIN: stage I (TYPE): ..." for any
/// problem, e.g. `pipeline.json: stage 3 (normals): unknown key "kk"; did you mean "k"?`.
Pipeline parse_pipeline(const std::string& json_text, const std::string& origin,
                        const std::vector<std::string>& overrides = {});
/// The same checks over steps given as text (the command line).
Pipeline build_pipeline(const std::vector<StepText>& steps, const std::string& origin);

struct RunOptions {
  bool no_clobber = false;  // an existing output file is a UsageError (before any work)
  /// Called when a stage starts; returns its progress callback (may be empty).
  std::function<ProgressCallback(const StageRecord&)> progress;
  /// Called when a stage has finished, with its record (summary line, warnings).
  std::function<void(const StageRecord&)> stage_done;
};

/// What a whole run did, for the report.
struct RunReport {
  std::string command;               // "run", or the CLI command
  std::string origin;
  std::vector<StageRecord> stages;
  std::vector<std::string> warnings; // every stage's warnings, "stage I (TYPE): ..." prefixed
  std::vector<std::string> outputs;  // files written
  double total_seconds = 0.0;
  double peak_rss_mb = 0.0;
  std::size_t tree_builds = 0;
  bool ok = false;
  std::string error;                 // the failure's message when !ok (Error::what())
  std::string error_kind;            // "usage", "input", "compute" or "cancelled" when !ok
  ErrorPlace error_place;            // where it happened, as far as known
  std::string error_message;         // the message without the stage prefix
  int exit_code = 0;

  /// Records `e` as the run's failure (ok false, the error's words, kind, place and exit code).
  void fail(const Error& e);
};

/// Checks the output paths (writable directory, known extension, no_clobber), then runs the
/// steps in order over `context`. On a failure the files this run wrote are removed, `report`
/// holds the records so far with `ok` false, and the error is rethrown. Not thread-safe on one
/// context.
void run_pipeline(const Pipeline& pipeline, Context& context, RunReport& report, const RunOptions& options = {});

/// The report as JSON text (the schema of docs/cli.md).
std::string report_json(const RunReport& report);

/// High-water resident memory of this process, MiB.
double peak_rss_mb();

}  // namespace pointsurf
