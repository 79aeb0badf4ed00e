// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Runs the pointsurf command line from the pipeline tests.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "support/files.h"

namespace pointsurf::test {

struct CliResult {
  int exit_code = -1;
  std::string out, err;
};

inline CliResult run_cli(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command = std::string(POINTSURF_CLI_PATH) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_bytes(out), read_bytes(err)};
}

}  // namespace pointsurf::test
