// SPDX-License-Identifier: GPL-3.0-or-later
// `pointsurf report RUN.json OUT.html`: its refusals and their exit codes.
#include <sys/wait.h>

#include <cstdlib>

#include <gtest/gtest.h>

#include "pointsurf/io/io.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(ReportCli, RefusesWhatItCannotUseWithTheReason) {
  const auto dir = test::temp_dir("report_cli");
  const std::string run = (dir / "run.json").string(), html = (dir / "r.html").string();
  write_point_cloud(dir / "c.ply", test::sample_sphere(300));
  test::RunResult r = test::run_cli("normals " + (dir / "c.ply").string() + " " + (dir / "n.ply").string() + " --quiet --report " + run, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = test::run_cli("report " + run, dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "expected RUN.json OUT.html, got 1 file name")) << r.err;
  r = test::run_cli("report " + (dir / "none.json").string() + " " + html, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "none.json: no such file")) << r.err;
  test::write_bytes(dir / "bad.json", "{\"stages\": [");
  r = test::run_cli("report " + (dir / "bad.json").string() + " " + html, dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "bad.json: not a run report (JSON)")) << r.err;
  r = test::run_cli("report " + run + " " + html + " --max-points 0", dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--max-points: \"0\" is not a positive integer")) << r.err;
  r = test::run_cli("report " + run + " " + (dir / "no" / "r.html").string(), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "does not exist")) << r.err;
  r = test::run_cli("report " + run + " " + html, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "3D view: 0 triangles, 300 points")) << r.err;  // the normals run wrote no mesh: the cloud as read
  // Without the JavaScript libraries: the package to install, and no page.
  std::filesystem::remove(html);
  const int code = std::system(("POINTSURF_JS_DIR=" + (dir / "nojs").string() + " " + POINTSURF_CLI_PATH + " report " + run + " " + html + " 2>" +
                                (dir / "err.txt").string())
                                   .c_str());
  EXPECT_EQ(WEXITSTATUS(code), 2);
  EXPECT_TRUE(test::contains(test::read_bytes(dir / "err.txt"), "install Debian's libjs-three")) << test::read_bytes(dir / "err.txt");
  EXPECT_FALSE(std::filesystem::exists(html));
}

}  // namespace
}  // namespace pointsurf
