// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/cli_run.h"

#include <sys/wait.h>

#include <cstdlib>

#include "support/files.h"

namespace pointsurf::test {

RunResult run_cli(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command = std::string(POINTSURF_CLI_PATH) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_bytes(out);
  r.err = read_bytes(err);
  return r;
}

}  // namespace pointsurf::test
