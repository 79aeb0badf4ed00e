// SPDX-License-Identifier: GPL-3.0-or-later
#include "cli_common.h"

#include <sys/resource.h>
#include <unistd.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <utility>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf::cli {

void add_common_options(CLI::App& cmd, CommonOptions& options) {
  cmd.add_option("--report", options.report_path, "Write a JSON report of the run (parameters, counts, timings) to FILE")
      ->type_name("FILE.json");
  cmd.add_option("--threads", options.threads, "Worker threads (default: all cores)")->type_name("N");
  cmd.add_flag("--quiet,-q", options.quiet, "No progress bar, no warnings on stderr (they still go to the report)");
  cmd.add_flag("--strict", options.strict, "Points with NaN/Inf coordinates are an error instead of being dropped and counted");
  cmd.add_option("--columns", options.columns,
                 "Column meaning of XYZ/TXT/CSV input, e.g. x,y,z,_,i,r,g,b (_ skips a column; other names become fields)")
      ->type_name("SPEC");
  cmd.add_option("--input-format", options.input_format, "Read the input as this format instead of detecting it")
      ->type_name("ply|xyz|pcd|las|off|obj|stl");
}

void add_output_options(CLI::App& cmd, OutputOptions& options) {
  cmd.add_flag("--ascii", options.ascii, "Write ascii PLY/PCD/STL instead of binary");
  cmd.add_flag("--float", options.single_precision,
               "Write float32 positions (PLY, PCD); refused for coordinates where float32 loses precision");
  cmd.add_flag("--big-endian", options.big_endian, "Write binary big-endian PLY");
  cmd.add_flag("--compressed", options.compressed, "Write PCD as binary_compressed (LZF)");
  cmd.add_option("--las-offset", options.las_offset, "LAS offset (default: near the data's minimum)")->type_name("X,Y,Z");
  cmd.add_option("--las-scale", options.las_scale, "LAS scale, cloud units per count (default 1e-4)")->type_name("S");
}

WriteOptions OutputOptions::to_write_options() const {
  WriteOptions w;
  w.ascii = ascii;
  if (ascii) w.ply_encoding = PlyEncoding::Ascii;
  else if (big_endian) w.ply_encoding = PlyEncoding::BinaryBigEndian;
  w.single_precision = single_precision;
  w.pcd_compressed = compressed;
  if (!las_offset.empty()) w.las_offset = parse_vector3(las_offset, "--las-offset");
  if (las_scale < 0.0 || !std::isfinite(las_scale)) throw UsageError(fmt::format("--las-scale: {} must be positive", las_scale));
  if (las_scale > 0.0) w.las_scale = las_scale;
  return w;
}

double peak_rss_mb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is KiB on Linux
}

Eigen::Vector3d parse_vector3(const std::string& text, const std::string& option) {
  Eigen::Vector3d v;
  std::stringstream ss(text);
  std::string item;
  int i = 0;
  while (std::getline(ss, item, ',')) {
    if (i >= 3) break;
    try {
      std::size_t used = 0;
      v[i] = std::stod(item, &used);
      if (used != item.size() || !std::isfinite(v[i])) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw UsageError(fmt::format("{}: '{}' is not a number (expected X,Y,Z)", option, item));
    }
    ++i;
  }
  if (i != 3 || std::getline(ss, item, ','))
    throw UsageError(fmt::format("{}: '{}': expected three comma-separated numbers X,Y,Z", option, text));
  return v;
}

Report::Report(std::string command) : start_(std::chrono::steady_clock::now()) {
  json_ = {{"command", std::move(command)},
           {"version", POINTSURF_VERSION},
           {"inputs", nlohmann::json::array()},
           {"outputs", nlohmann::json::array()},
           {"parameters", nlohmann::json::object()},
           {"stages", nlohmann::json::array()},
           {"total_seconds", 0.0},
           {"peak_rss_mb", 0.0},
           {"warnings", nlohmann::json::array()}};
}

void Report::warn(const std::string& message, bool quiet) {
  json_["warnings"].push_back(message);
  if (!quiet) fmt::print(stderr, "warning: {}\n", message);
}

std::size_t Report::begin_stage(const std::string& name) {
  json_["stages"].push_back({{"name", name},
                             {"seconds", 0.0},
                             {"peak_rss_mb", 0.0},
                             {"counts", nlohmann::json::object()},
                             {"metrics", nlohmann::json::object()}});
  stage_starts_.push_back(std::chrono::steady_clock::now());
  return stage_starts_.size() - 1;
}

void Report::end_stage(std::size_t index) {
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - stage_starts_[index]).count();
  json_["stages"][index]["seconds"] = seconds;
  json_["stages"][index]["peak_rss_mb"] = peak_rss_mb();
}

void Report::finish() {
  json_["total_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  json_["peak_rss_mb"] = peak_rss_mb();
}

void Report::write(const std::filesystem::path& path) const {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : std::filesystem::path(".");
  const std::filesystem::path tmp = dir / fmt::format(".{}.tmp-{}", path.filename().string(), ::getpid());
  {
    std::ofstream out(tmp);
    if (!out) throw Error(fmt::format("{}: cannot write the report", path.string()));
    out << json_.dump(2) << '\n';
    out.close();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw Error(fmt::format("{}: cannot write the report", path.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(fmt::format("{}: cannot write the report: {}", path.string(), ec.message()));
  }
}

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled && ::isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

ProgressBar::~ProgressBar() {
  if (shown_) {
    if (last_fraction_ < 1.0) update(1.0);
    std::fputc('\n', stderr);
  }
}

ProgressCallback ProgressBar::callback() {
  if (!enabled_) return {};
  return [this](double fraction) {
    update(fraction);
    return true;
  };
}

void ProgressBar::update(double fraction) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < 1.0 && fraction < 1.0) return;
  if (shown_ && fraction < 1.0 && now - last_ < std::chrono::milliseconds(100)) return;
  last_ = now;
  shown_ = true;
  fraction = std::clamp(fraction, 0.0, 1.0);
  last_fraction_ = fraction;
  constexpr int width = 30;
  const int filled = static_cast<int>(fraction * width);
  fmt::print(stderr, "\r{:<10} [{}{}] {:3.0f}%  {:.1f} s", label_, std::string(filled, '#'), std::string(width - filled, '.'),
             100.0 * fraction, elapsed);
  std::fflush(stderr);
}

namespace {

nlohmann::json describe_cloud(const std::filesystem::path& path, const std::string& format, const PointCloud& cloud) {
  nlohmann::json fields = nlohmann::json::array();
  for (const ScalarField& f : cloud.fields) fields.push_back(f.name);
  return {{"path", path.string()},     {"format", format},
          {"points", cloud.size()},    {"normals", cloud.has_normals()},
          {"colors", cloud.has_colors()}, {"fields", fields}};
}

}  // namespace

std::string ascii_lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

std::string with_file(const std::filesystem::path& path, const std::string& message) {
  // Some readers name the file in their warnings already.
  if (message.rfind(path.string(), 0) == 0) return message;
  return fmt::format("{}: {}", path.string(), message);
}

CloudReadResult read_cloud_reported(const std::filesystem::path& path, const CommonOptions& common, Report& report) {
  const std::size_t stage = report.begin_stage("read");
  ReadOptions options;
  options.strict = common.strict;
  options.columns = common.columns;
  options.format = ascii_lower(common.input_format);
  CloudReadResult result = read_point_cloud(path, options);
  report.end_stage(stage);
  nlohmann::json& s = report.stage(stage);
  s["counts"]["points"] = result.cloud.size();
  s["counts"]["dropped_nonfinite"] = result.dropped_nonfinite;
  nlohmann::json input = describe_cloud(path, result.format, result.cloud);
  input["encoding"] = result.encoding;
  input["faces"] = result.face_count;
  input["dropped_nonfinite"] = result.dropped_nonfinite;
  report.add_input(input);
  for (const std::string& w : result.warnings) report.warn(with_file(path, w), common.quiet);
  if (result.dropped_nonfinite > 0)
    report.warn(fmt::format("{}: {} points with NaN/Inf coordinates dropped (--strict makes this an error)", path.string(),
                            result.dropped_nonfinite),
                common.quiet);
  if (result.cloud.empty()) throw InputError(fmt::format("{}: no points", path.string()));
  return result;
}

void warn_lost_attributes(const std::filesystem::path& path, bool normals, bool colors, const FieldSet& fields, std::size_t faces,
                          const WriteOptions& options, const CommonOptions& common, Report& report) {
  const std::string format = options.format.empty() ? format_from_extension(path) : options.format;
  std::vector<std::string> lost;
  const bool holds_faces = format == "ply" || format == "off" || format == "obj" || format == "stl";
  if (faces > 0 && !holds_faces) lost.push_back(fmt::format("{} faces", faces));
  if (format == "stl") {
    if (normals) lost.push_back("normals");
    if (colors) lost.push_back("colours");
  }
  if (format == "las" && normals) lost.push_back("normals");
  if (format == "xyz" && ascii_lower(path.extension().string()) != ".csv" && !fields.empty()) lost.push_back("field names (values are kept as columns)");
  if (format == "off" || format == "obj" || format == "stl") {
    for (const ScalarField& f : fields) lost.push_back(fmt::format("field '{}'", f.name));
  } else if (format == "las") {
    // The slots write_las fills (formats 6 and 7 have no NIR).
    static const char* const las_fields[] = {"intensity", "return_number", "number_of_returns", "classification",
                                             "gps_time",  "user_data",     "scan_angle",        "point_source_id"};
    for (const ScalarField& f : fields) {
      const bool known = std::any_of(std::begin(las_fields), std::end(las_fields), [&](const char* n) { return f.name == n; });
      if (!known) lost.push_back(fmt::format("field '{}'", f.name));
    }
  }
  if (!lost.empty()) {
    std::string list;
    for (const std::string& l : lost) list += (list.empty() ? "" : ", ") + l;
    report.warn(fmt::format("{}: the {} format cannot hold: {}", path.string(), format, list), common.quiet);
  }
}

void write_cloud_reported(const std::filesystem::path& path, const PointCloud& cloud, const OutputOptions& out,
                          const CommonOptions& common, Report& report) {
  const WriteOptions options = out.to_write_options();
  warn_lost_attributes(path, cloud.has_normals(), cloud.has_colors(), cloud.fields, 0, options, common, report);
  const std::size_t stage = report.begin_stage("write");
  write_point_cloud(path, cloud, options);
  report.end_stage(stage);
  report.stage(stage)["counts"]["points"] = cloud.size();
  report.add_output(describe_cloud(path, format_from_extension(path), cloud));
}

void estimate_missing_normals(PointCloud& cloud, const KdTree& tree, int k, const CommonOptions& common, Report& report) {
  const std::size_t stage = report.begin_stage("normals");
  NormalResult estimated;
  OrientResult oriented;
  {
    ProgressBar bar("normals", !common.quiet);
    estimated = estimate_normals(cloud, {.k = k, .keep_variation = false}, &tree, bar.callback());
    oriented = orient_normals(cloud, {}, &tree, bar.callback());
  }
  report.end_stage(stage);
  report.stage(stage)["counts"] = {
      {"points", cloud.size()}, {"degenerate", estimated.degenerate}, {"flipped", oriented.flipped}, {"components", oriented.components}};
  report.stage(stage)["metrics"] = {{"k", k}, {"orientation", "mst"}, {"reason", "the input has no normals"}};
}

namespace {
std::vector<std::pair<int, CommandFactory>>& command_registry() {
  static std::vector<std::pair<int, CommandFactory>> registry;  // built during static initialisation
  return registry;
}
}  // namespace

CommandRegistration::CommandRegistration(int order, CommandFactory factory) { command_registry().emplace_back(order, factory); }

std::vector<CommandFactory> registered_commands() {
  auto entries = command_registry();
  std::stable_sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<CommandFactory> factories;
  for (const auto& entry : entries) factories.push_back(entry.second);
  return factories;
}

}  // namespace pointsurf::cli
