// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf: from a raw 3D scan to a verified surface. The stage commands come from the
// pipeline registry; info, convert and run are the tool's own.
// Exit codes: 0 ok, 1 usage error, 2 bad input, 3 failure while computing.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <new>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/pipeline/registry.h"

namespace {

std::vector<pointsurf::cli::Command> all_commands() {
  using namespace pointsurf::cli;
  std::vector<Command> commands = {info_command(), convert_command()};
  for (Command& c : stage_commands()) commands.push_back(std::move(c));
  commands.push_back(run_command());
  commands.push_back(report_command());
  commands.push_back(stages_command());
  return commands;
}

std::string main_help(const std::vector<pointsurf::cli::Command>& commands) {
  std::string out = "pointsurf " POINTSURF_VERSION
                    ": from a raw 3D scan (point cloud) to a verified surface.\n"
                    "Formats (detected from content): " +
                    pointsurf::known_format_names(", ") +
                    " (see docs/formats.md).\n"
                    "Exit codes: 0 ok, 1 usage error, 2 bad input, 3 failure while computing.\n\n"
                    "Usage: pointsurf COMMAND [ARGS] [options]    (pointsurf COMMAND --help for its options and defaults)\n\n"
                    "Commands:\n";
  for (const auto& c : commands) out += fmt::format("  {:<12} {}\n", c.name, c.summary);
  out += "\nExamples:\n"
         "  pointsurf info data/b9_training.ply --json\n"
         "  pointsurf normals data/kitten.xyz oriented.ply --k 30 --orient mst --report run.json\n"
         "  pointsurf run examples/kitten_mesh.json --set normals.k=20\n";
  return out;
}

// Threads for the library: tbb's limit for the duration of the command.
int threads_from(const std::vector<std::string>& args) {
  for (std::size_t i = 0; i < args.size(); ++i) {
    std::string v;
    if (args[i] == "--threads" && i + 1 < args.size()) v = args[i + 1];
    else if (args[i].rfind("--threads=", 0) == 0) v = args[i].substr(10);
    else continue;
    try {
      return std::max(0, std::stoi(v));
    } catch (const std::exception&) {
      return 0;  // the command's own scan reports the bad value
    }
  }
  return 0;
}

// Large arrays on transparent huge pages. glibc's malloc madvises them only when the tunable
// glibc.malloc.hugetlb=1 is set, and reads tunables at start-up, so the command sets it and
// starts itself again (once: the variable is then set). Measured on a 2-core VM: evaluate of 1M
// points against 1.2M triangles took 157k page faults and 4.6-5.3 s without, 21k and 4.1 s with
// (bench/notes/evaluate.md). POINTSURF_NO_HUGE_PAGES=1, a GLIBC_TUNABLES that already names the
// tunable, or a kernel with huge pages off leave the process as it is; so does a failed exec.
void restart_with_huge_pages(char** argv) {
  if (std::getenv("POINTSURF_NO_HUGE_PAGES") != nullptr) return;
  const char* set = std::getenv("GLIBC_TUNABLES");
  const std::optional<std::string> tunables = set != nullptr ? std::optional<std::string>(set) : std::nullopt;
  if (tunables && tunables->find("glibc.malloc.hugetlb") != std::string::npos) return;
  std::ifstream mode("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string line;
  if (!std::getline(mode, line) || line.find("[never]") != std::string::npos) return;
  const std::string value = (tunables && !tunables->empty() ? *tunables + ":" : std::string()) + "glibc.malloc.hugetlb=1";
  if (::setenv("GLIBC_TUNABLES", value.c_str(), 1) != 0) return;
  ::execv("/proc/self/exe", argv);
  ::unsetenv("GLIBC_TUNABLES");  // the exec failed: go on as we are
  if (tunables) ::setenv("GLIBC_TUNABLES", tunables->c_str(), 1);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace pointsurf;
  restart_with_huge_pages(argv);
  const std::vector<cli::Command> commands = all_commands();
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty()) {
    fmt::print(stderr, "{}\npointsurf: error: a command is required\n", main_help(commands));
    return 1;
  }
  const std::string name = args.front();
  if (name == "--help" || name == "-h" || name == "help") {
    fmt::print("{}", main_help(commands));
    return 0;
  }
  if (name == "--version") {
    fmt::print("{}\n", POINTSURF_VERSION);
    return 0;
  }
  const cli::Command* command = nullptr;
  for (const cli::Command& c : commands)
    if (c.name == name) command = &c;
  if (command == nullptr) {
    std::vector<std::string> names;
    for (const cli::Command& c : commands) names.push_back(c.name);
    const std::string near = closest_name(name, names);
    fmt::print(stderr, "pointsurf: error: unknown command \"{}\"{}\n", name,
               near.empty() ? " (see pointsurf --help)" : fmt::format("; did you mean \"{}\"?", near));
    return 1;
  }
  args.erase(args.begin());
  cli::install_interrupt_handler();
  try {
    std::optional<tbb::global_control> threads;
    if (const int n = threads_from(args); n > 0)
      threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(n));
    return command->run(args);
  } catch (const Error& e) {
    fmt::print(stderr, "pointsurf {}: error: {}\n", name, command->words ? command->words(e) : std::string(e.what()));
    return e.exit_code();
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "pointsurf {}: error: out of memory\n", name);
    return 3;
  } catch (const std::exception& e) {
    fmt::print(stderr, "pointsurf {}: error: {}\n", name, e.what());
    return 3;
  }
}
