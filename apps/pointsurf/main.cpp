// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf: from a raw 3D scan to a verified surface.
// Exit codes: 0 ok, 1 usage error, 2 bad input, 3 failure while computing.
#include <cstdio>
#include <exception>
#include <memory>
#include <new>
#include <optional>
#include <vector>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <tbb/global_control.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"

int main(int argc, char** argv) {
  using namespace pointsurf;
  CLI::App app{"pointsurf " POINTSURF_VERSION
               ": from a raw 3D scan (point cloud) to a verified surface.\n"
               "Formats (detected from content): PLY, XYZ/PTS/TXT/CSV, PCD, LAS 1.0-1.4, OFF, OBJ, STL.\n"
               "Exit codes: 0 ok, 1 usage error, 2 bad input, 3 failure while computing.",
               "pointsurf"};
  app.footer(
      "Examples:\n"
      "  pointsurf info scan.las --json\n"
      "  pointsurf convert scan.pcd scan.ply\n"
      "  pointsurf normals scan.xyz oriented.ply --k 30 --orient mst --report run.json\n"
      "Every command takes --report FILE.json, --threads N, --quiet, --strict; see 'pointsurf COMMAND --help'.");
  app.require_subcommand(1);
  app.set_version_flag("--version", POINTSURF_VERSION);
  std::vector<cli::Command> commands;
  for (cli::CommandFactory factory : cli::registered_commands()) commands.push_back(factory(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help, version or the error message
    return code == 0 ? 0 : 1;
  }

  for (cli::Command& command : commands) {
    if (!command.app->parsed()) continue;
    try {
      if (command.common->threads < 0) throw UsageError(fmt::format("--threads: {} must be >= 0", command.common->threads));
      std::optional<tbb::global_control> threads;
      if (command.common->threads > 0)
        threads.emplace(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(command.common->threads));
      command.run();
      return 0;
    } catch (const Error& e) {
      fmt::print(stderr, "pointsurf {}: error: {}\n", command.app->get_name(), e.what());
      return e.exit_code();
    } catch (const std::bad_alloc&) {
      fmt::print(stderr, "pointsurf {}: error: out of memory\n", command.app->get_name());
      return 3;
    } catch (const std::exception& e) {
      fmt::print(stderr, "pointsurf {}: error: {}\n", command.app->get_name(), e.what());
      return 3;
    }
  }
  return 1;
}
