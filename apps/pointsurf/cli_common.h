// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Shared pieces of the pointsurf subcommands: common options, the JSON run report, the
// progress bar and reading/writing with the report's bookkeeping.
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "pointsurf/core/progress.h"
#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {

/// Options every subcommand takes.
struct CommonOptions {
  std::string report_path;  // --report FILE.json
  int threads = 0;          // --threads N (0: all cores)
  bool quiet = false;       // --quiet
  bool strict = false;      // --strict: NaN/Inf coordinates are an error
  std::string columns;      // --columns for XYZ-family input
  std::string input_format; // --input-format to override detection
};

/// Options of commands that write a file.
struct OutputOptions {
  bool ascii = false;
  bool single_precision = false;
  bool big_endian = false;
  bool compressed = false;
  std::string las_offset;  // "X,Y,Z"
  double las_scale = 0.0;
  WriteOptions to_write_options() const;
};

void add_common_options(CLI::App& cmd, CommonOptions& options);
void add_output_options(CLI::App& cmd, OutputOptions& options);

/// Peak resident memory of this process so far, MiB.
double peak_rss_mb();

/// Parses "X,Y,Z" into a vector; throws UsageError naming the option on failure.
Eigen::Vector3d parse_vector3(const std::string& text, const std::string& option);

/// The run report: the one JSON schema that every stage extends.
///   command, version, inputs, outputs, parameters, stages [{name, seconds, peak_rss_mb,
///   counts, metrics}], total_seconds, peak_rss_mb, warnings.
class Report {
public:
  explicit Report(std::string command);
  nlohmann::json& parameters() { return json_["parameters"]; }
  void add_input(const nlohmann::json& input) { json_["inputs"].push_back(input); }
  void add_output(const nlohmann::json& output) { json_["outputs"].push_back(output); }
  void warn(const std::string& message, bool quiet);
  /// Opens a stage record; finish it with end_stage(). Returns its index.
  std::size_t begin_stage(const std::string& name);
  nlohmann::json& stage(std::size_t index) { return json_["stages"][index]; }
  void end_stage(std::size_t index);
  /// Fills total_seconds and peak_rss_mb.
  void finish();
  const nlohmann::json& json() const { return json_; }
  /// Writes the report atomically (temporary file renamed).
  void write(const std::filesystem::path& path) const;

private:
  nlohmann::json json_;
  std::chrono::steady_clock::time_point start_;
  std::vector<std::chrono::steady_clock::time_point> stage_starts_;
};

/// A one-line progress bar on stderr, shown only when stderr is a terminal, not --quiet, and
/// the work has lasted more than about a second.
class ProgressBar {
public:
  ProgressBar(std::string label, bool enabled);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;
  /// A callback for the library; never cancels.
  ProgressCallback callback();
  void update(double fraction);

private:
  std::string label_;
  bool enabled_;
  bool shown_ = false;
  double last_fraction_ = 0.0;
  std::chrono::steady_clock::time_point start_, last_;
};

/// ASCII lower case (format names and extensions are matched case-insensitively).
std::string ascii_lower(std::string text);

/// "path: message", unless the message already starts with the path.
std::string with_file(const std::filesystem::path& path, const std::string& message);

/// Reads a cloud (or a mesh's vertices) with the common options and records input, read stage
/// and warnings in the report.
CloudReadResult read_cloud_reported(const std::filesystem::path& path, const CommonOptions& common, Report& report);
/// Writes a cloud and records the output and the write stage.
void write_cloud_reported(const std::filesystem::path& path, const PointCloud& cloud, const OutputOptions& out,
                          const CommonOptions& common, Report& report);

/// Adds the warnings about attributes the output format cannot hold.
void warn_lost_attributes(const std::filesystem::path& path, bool normals, bool colors, const FieldSet& fields, std::size_t faces,
                          const WriteOptions& options, const CommonOptions& common, Report& report);

/// For commands that need oriented normals on input that has none: PCA normals over `k`
/// neighbours (no variation field) and MST orientation, reusing `tree` (built over
/// cloud.positions), recorded as a report stage "normals" with its counts.
void estimate_missing_normals(PointCloud& cloud, const KdTree& tree, int k, const CommonOptions& common, Report& report);

/// A registered subcommand: its CLI11 app and the function that runs it after parsing.
struct Command {
  CLI::App* app = nullptr;
  std::function<void()> run;
  CommonOptions* common = nullptr;
};

/// Subcommands register themselves: each cmd_*.cpp holds one
///   `const CommandRegistration registration{order, register_X};`
/// at namespace scope, and main() adds them in ascending `order` (the order of `--help`, which
/// follows the data flow: 10 info, 20 convert, 30 clean, 40 simplify, 50 normals, 60 curvature,
/// 70 features, ..., 120 reconstruct).
using CommandFactory = Command (*)(CLI::App& app);
struct CommandRegistration {
  CommandRegistration(int order, CommandFactory factory);
};
/// The registered factories sorted by order.
std::vector<CommandFactory> registered_commands();

}  // namespace pointsurf::cli
