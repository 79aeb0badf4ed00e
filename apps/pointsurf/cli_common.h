// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What every pointsurf command shares: the argument scanner (options in the tool's own words,
// with "did you mean"), the common options, the progress bar, and writing the run report.
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "pointsurf/core/progress.h"
#include "progress_display.h"
#include "pointsurf/pipeline/pipeline.h"
#include "pointsurf/report/html_report.h"

namespace pointsurf::cli {

/// "std_ratio" -> "--std-ratio".
std::string dashed(const std::string& key);

/// One command-line option: --name, whether it takes a value, and where the value goes.
struct OptionDef {
  std::string name;        // "--k"
  bool flag = false;       // takes no value ("--quiet"); "--name=false" is accepted too
  std::string meta;        // value placeholder for messages
  std::function<void(const std::string& value)> set;  // called with the value ("true" for a flag)
};

/// Scans `args`: positionals in order, options by name (`--k 30`, `--k=30`, flags, `--no-FLAG`).
/// Throws UsageError for an unknown option (with "did you mean"), a missing value, or `-h`.
std::vector<std::string> scan_arguments(const std::vector<std::string>& args, const std::vector<OptionDef>& options);

/// Options every command takes.
struct CommonOptions {
  std::string report_path;
  int threads = 0;
  bool quiet = false;
  bool no_clobber = false;
  bool help = false;
};
void add_common_options(std::vector<OptionDef>& options, CommonOptions& common);
/// Help lines of the common options.
std::string common_options_help();
/// Checks --threads and --report before any work (UsageError).
void check_common_options(const CommonOptions& common);

/// The progress trace asked for by the environment variable POINTSURF_PROGRESS_TRACE=FILE: one
/// tab-separated line per event, "seconds index stage event value", where seconds count from
/// the stage's start and event is "start", "fraction" (value in [0, 1]), "phase" (its name) or
/// "end" (the stage's seconds). For benchmarks and tests; written with or without a terminal.
class ProgressTrace {
public:
  explicit ProgressTrace(const std::string& path);
  void record(double seconds, std::size_t index, const std::string& stage, std::string_view event, std::string_view value);

private:
  std::mutex mutex_;
  std::ofstream out_;
};

/// A one-line progress bar on stderr, shown only on a terminal, without --quiet, and once the
/// work has lasted about a second (ProgressDisplay): the stage, the fraction, the running clock,
/// the time left and the phase. A ticker thread redraws it while the stage reports nothing.
class ProgressBar {
public:
  ProgressBar(std::string label, bool enabled, std::size_t index = 0, std::string stage = {}, ProgressTrace* trace = nullptr);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  void update(double fraction);
  void phase(std::string_view name);
  /// Stops the ticker and clears the line; `seconds` >= 0 ends the trace's stage.
  void finish(double seconds = -1.0);

private:
  double now() const;
  void tick();

  ProgressDisplay display_;
  bool enabled_;
  bool shown_ = false;
  std::size_t index_;
  std::string stage_;
  ProgressTrace* trace_;
  double last_traced_s_ = -1.0;  // update() runs on one thread at a time (the ProgressCallback contract)
  std::chrono::steady_clock::time_point start_;
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;
  bool stop_ = false;
  std::thread ticker_;
};

/// Ctrl-C: the first SIGINT asks the running stage to stop at its next progress report (it then
/// fails with CancelledError: the report says "cancelled", no output is left, exit 130); a second
/// one ends the process at once. Not installed when SIGINT was inherited ignored (a background job).
void install_interrupt_handler();
/// True once SIGINT arrived.
bool interrupt_requested() noexcept;

/// Runs `pipeline` with the CLI's progress bars, summary lines and warnings on stderr, then
/// writes the report (also on failure) when asked. Rethrows the run's error. `report_text`, when
/// given, receives the report's JSON after a successful run.
void run_with_report(const Pipeline& pipeline, const CommonOptions& common, const std::string& command, std::string* report_text = nullptr);
/// build_pipeline(steps, origin) for `command`; when the steps are refused (a value out of range,
/// an unknown key) the report, when asked, is written with the error before it is rethrown.
Pipeline build_with_report(const std::vector<StepText>& steps, const std::string& origin, const CommonOptions& common,
                           const std::string& command);
/// Writes, when --report was given, the report of a run refused before any work: `e` and where.
/// A failure to write it is ignored (the run's own error matters more).
void write_failure_report(const CommonOptions& common, const std::string& command, const std::string& origin, const Error& e);
/// Writes the HTML report of a run (its JSON text, named `origin`) to `out_path` (cmd_report.cpp).
void write_html_report(const std::string& run_json, const std::string& origin, const std::string& out_path, const HtmlReportParams& params,
                       const CommonOptions& common);

/// Writes `text` to `path` through a temporary file renamed at the end.
void write_text_atomically(const std::filesystem::path& path, const std::string& text);

/// A command of the tool: name, one-line summary, its run function (arguments after the
/// command name) and its help text.
struct Command {
  std::string name, summary;
  std::function<int(const std::vector<std::string>& args)> run;
  std::function<std::string()> help;
  /// How the command writes an error (empty: Error::what(), the pipeline's wording).
  std::function<std::string(const Error&)> words;
};
/// An error in a one-stage command's words: no stage prefix (the command is the stage), and a
/// parameter key written as its option ("--k: 0 is out of range [1, inf)").
std::string cli_words(const Error& e);
std::vector<Command> stage_commands();
Command info_command();
Command convert_command();
Command run_command();
Command report_command();
Command stages_command();

}  // namespace pointsurf::cli
