// SPDX-License-Identifier: GPL-3.0-or-later
#include "cli_common.h"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <fstream>
#include <memory>
#include <thread>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/registry.h"

namespace pointsurf::cli {

std::string dashed(const std::string& key) {
  std::string out = "--" + key;
  std::replace(out.begin(), out.end(), '_', '-');
  return out;
}

std::vector<std::string> scan_arguments(const std::vector<std::string>& args, const std::vector<OptionDef>& options) {
  std::vector<std::string> positionals;
  auto find = [&](const std::string& name) -> const OptionDef* {
    for (const OptionDef& o : options)
      if (o.name == name) return &o;
    return nullptr;
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg.size() < 2 || arg[0] != '-' || (arg[1] != '-' && (std::isdigit(static_cast<unsigned char>(arg[1])) || arg[1] == '.'))) {
      positionals.push_back(arg);
      continue;
    }
    if (arg == "--") {
      positionals.insert(positionals.end(), args.begin() + static_cast<std::ptrdiff_t>(i) + 1, args.end());
      break;
    }
    std::string name = arg, value;
    bool has_value = false;
    if (const std::size_t eq = arg.find('='); eq != std::string::npos) {
      name = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_value = true;
    }
    if (name == "-h") name = "--help";
    if (name == "-q") name = "--quiet";
    const OptionDef* o = find(name);
    if (o == nullptr && name.rfind("--no-", 0) == 0 && !has_value) {
      // --no-close-small-holes: the flag set to false.
      const OptionDef* flag = find("--" + name.substr(5));
      if (flag != nullptr && flag->flag) {
        flag->set("false");
        continue;
      }
    }
    if (o == nullptr) {
      std::vector<std::string> names;
      for (const OptionDef& d : options) names.push_back(d.name);
      const std::string near = closest_name(name, names);
      throw UsageError(fmt::format("unknown option {}{}", name, near.empty() ? "" : fmt::format("; did you mean {}?", near)));
    }
    if (o->flag) {
      o->set(has_value ? value : "true");
      continue;
    }
    if (!has_value) {
      if (i + 1 >= args.size()) throw UsageError(fmt::format("{} needs a value ({})", name, o->meta.empty() ? "VALUE" : o->meta));
      value = args[++i];
    }
    o->set(value);
  }
  return positionals;
}

void add_common_options(std::vector<OptionDef>& options, CommonOptions& common) {
  options.push_back({"--report", false, "FILE.json", [&common](const std::string& v) { common.report_path = v; }});
  options.push_back({"--threads", false, "N", [&common](const std::string& v) {
                       std::size_t used = 0;
                       int n = -1;
                       try {
                         n = std::stoi(v, &used);
                       } catch (const std::exception&) {
                         used = 0;
                       }
                       if (used != v.size() || n < 0) throw UsageError(fmt::format("--threads: \"{}\" is not a count >= 0", v));
                       common.threads = n;
                     }});
  auto flag = [](bool& target, const char* name) {
    return [&target, name](const std::string& v) {
      if (v != "true" && v != "false") throw UsageError(fmt::format("{}: \"{}\" is not true or false", name, v));
      target = v == "true";
    };
  };
  options.push_back({"--quiet", true, "", flag(common.quiet, "--quiet")});
  options.push_back({"--no-clobber", true, "", flag(common.no_clobber, "--no-clobber")});
  options.push_back({"--help", true, "", flag(common.help, "--help")});
}

std::string common_options_help() {
  return "Common options:\n"
         "  --report FILE.json   Write the JSON run report (parameters used, counts, seconds, memory, warnings), also on failure\n"
         "  --threads N          Worker threads (default 0: all cores; at most the number of cores)\n"
         "  --quiet, -q          No progress bar, summary lines or warnings on stderr (the report keeps them)\n"
         "  --no-clobber         Refuse to overwrite an existing output file\n"
         "  --help, -h           This help\n";
}

void check_common_options(const CommonOptions& common) {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  if (common.threads > static_cast<int>(cores))
    throw UsageError(fmt::format("--threads: {} exceeds the {} cores of this machine", common.threads, cores));
  if (!common.report_path.empty()) {
    if (std::filesystem::path(common.report_path).extension() != ".json")
      throw UsageError(fmt::format("--report: {}: expected a .json file name", common.report_path));
    check_output_path(common.report_path, false, "json");
  }
}

ProgressTrace::ProgressTrace(const std::string& path) : out_(path) {
  if (!out_) throw UsageError(fmt::format("POINTSURF_PROGRESS_TRACE: cannot write {}", path));
  out_ << "# pointsurf progress trace: seconds\tindex\tstage\tevent\tvalue\n";
}

void ProgressTrace::record(double seconds, std::size_t index, const std::string& stage, std::string_view event, std::string_view value) {
  std::lock_guard lock(mutex_);
  out_ << fmt::format("{:.6f}\t{}\t{}\t{}\t{}\n", seconds, index, stage, event, value);
  if (event != "fraction") out_.flush();
}

ProgressBar::ProgressBar(std::string label, bool enabled, std::size_t index, std::string stage, ProgressTrace* trace)
    : display_(std::move(label)),
      enabled_(enabled && ::isatty(STDERR_FILENO)),
      index_(index),
      stage_(std::move(stage)),
      trace_(trace),
      start_(std::chrono::steady_clock::now()) {
  if (trace_) trace_->record(0.0, index_, stage_, "start", "");
  if (enabled_) ticker_ = std::thread([this] { tick(); });
}

ProgressBar::~ProgressBar() { finish(); }

double ProgressBar::now() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }

// The ticker: the only thread that draws, so a stage's workers never wait on the terminal.
void ProgressBar::tick() {
  std::unique_lock lock(stop_mutex_);
  while (!stop_cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stop_; })) {
    if (const std::optional<std::string> line = display_.due(now())) {
      fmt::print(stderr, "\r{}\033[K", *line);
      std::fflush(stderr);
      shown_ = true;
    }
  }
}

void ProgressBar::finish(double seconds) {
  if (ticker_.joinable()) {
    {
      std::lock_guard lock(stop_mutex_);
      stop_ = true;
    }
    stop_cv_.notify_all();
    ticker_.join();
  }
  if (shown_) {
    std::fputs("\r\033[K", stderr);  // the summary line takes its place
    std::fflush(stderr);
    shown_ = false;
  }
  enabled_ = false;
  if (trace_ && seconds >= 0.0) {
    trace_->record(now(), index_, stage_, "end", fmt::format("{:.6f}", seconds));
    trace_ = nullptr;
  }
}

void ProgressBar::update(double fraction) {
  const double t = now();
  // A trace line per millisecond at most (a parallel loop may report a million times): the
  // gaps it shows are then at most 1 ms longer than the true ones.
  if (trace_ && (t - last_traced_s_ >= 0.001 || fraction >= 1.0)) {
    last_traced_s_ = t;
    trace_->record(t, index_, stage_, "fraction", fmt::format("{:.6f}", fraction));
  }
  if (enabled_) display_.set_fraction(fraction, t);
}

void ProgressBar::phase(std::string_view name) {
  if (trace_) trace_->record(now(), index_, stage_, "phase", name);
  if (enabled_) display_.set_phase(name);
}

void write_text_atomically(const std::filesystem::path& path, const std::string& text) { write_file_atomically(path, text); }

namespace {
volatile std::sig_atomic_t g_interrupted = 0;

extern "C" void on_interrupt(int) {
  if (g_interrupted) {  // the second Ctrl-C: no more waiting
    std::signal(SIGINT, SIG_DFL);
    std::raise(SIGINT);
  }
  g_interrupted = 1;
}
}  // namespace

void install_interrupt_handler() {
  struct sigaction old {};
  if (::sigaction(SIGINT, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) return;
  struct sigaction action {};
  action.sa_handler = on_interrupt;
  sigemptyset(&action.sa_mask);
  ::sigaction(SIGINT, &action, nullptr);
}

bool interrupt_requested() noexcept { return g_interrupted != 0; }

void write_failure_report(const CommonOptions& common, const std::string& command, const std::string& origin, const Error& e) {
  if (common.report_path.empty()) return;
  RunReport failed;
  failed.command = command;
  failed.origin = origin;
  failed.fail(e);
  try {
    write_text_atomically(common.report_path, report_json(failed));
  } catch (const Error&) {
  }
}

Pipeline build_with_report(const std::vector<StepText>& steps, const std::string& origin, const CommonOptions& common,
                           const std::string& command) {
  try {
    return build_pipeline(steps, origin);
  } catch (const Error& e) {
    write_failure_report(common, command, origin, e);
    throw;
  }
}

void run_with_report(const Pipeline& pipeline, const CommonOptions& common, const std::string& command, std::string* report_text) {
  Context context;
  RunReport report;
  report.command = command;
  RunOptions options;
  options.no_clobber = common.no_clobber;
  std::unique_ptr<ProgressBar> bar;
  std::unique_ptr<ProgressTrace> trace;
  if (const char* path = std::getenv("POINTSURF_PROGRESS_TRACE"); path != nullptr && *path != '\0')
    trace = std::make_unique<ProgressTrace>(path);
  const std::size_t n = pipeline.steps.size();
  options.progress = [&](const StageRecord& r) -> ProgressCallback {
    bar.reset();  // the previous stage's ticker stops before the next one starts
    bar = std::make_unique<ProgressBar>(fmt::format("[{}/{}] {}", r.index, n, r.type), !common.quiet, r.index, r.type, trace.get());
    ProgressBar* b = bar.get();
    PhasedProgress progress;
    progress.on_fraction = [b](double f) {
      b->update(f);
      return !interrupt_requested();  // false: the stage stops (CancelledError)
    };
    progress.on_phase = [b](std::string_view name) { b->phase(name); };
    return progress;
  };
  options.stage_done = [&](const StageRecord& r) {
    if (bar) bar->finish(r.seconds);
    if (common.quiet) return;
    fmt::print(stderr, "[{}/{}] {} ({:.2f} s)\n", r.index, n, r.summary, r.seconds);
    for (const std::string& w : r.warnings) fmt::print(stderr, "warning: {}\n", w);
  };
  try {
    run_pipeline(pipeline, context, report, options);
  } catch (...) {
    if (bar) bar->finish();
    if (!common.report_path.empty()) {
      try {
        write_text_atomically(common.report_path, report_json(report));
      } catch (const Error&) {
        // The run's own error matters more.
      }
    }
    throw;
  }
  if (!common.report_path.empty()) write_text_atomically(common.report_path, report_json(report));
  if (report_text) *report_text = report_json(report);
}

}  // namespace pointsurf::cli
