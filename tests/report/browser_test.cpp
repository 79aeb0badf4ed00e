// SPDX-License-Identifier: GPL-3.0-or-later
// The real browser test: a pipeline's HTML report opened in headless Chromium with software
// WebGL (tests/report/browser_check.py over the DevTools protocol). Skipped, with the reason
// printed, only when Chromium cannot start here.
#include <sys/wait.h>

#include <cstdlib>

#include <gtest/gtest.h>

#include "pointsurf/render/image.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(BrowserReport, OpensOfflineDrawsA3DViewThatOrbitsWithoutErrors) {
  const auto dir = test::temp_dir("report_browser");
  const std::string kitten = test::data_path("kitten.xyz").string();
  const std::string pipeline = "[\"" + kitten + "\", {\"type\": \"normals\", \"tag\": \"oriented\", \"orient\": \"mst\"}, " +
                               "{\"type\": \"reconstruct\", \"method\": \"triangulate\"}, \"" + (dir / "mesh.ply").string() + "\", " +
                               "{\"type\": \"evaluate\"}, \"" + (dir / "deviation.ply").string() + "\"]";
  test::write_bytes(dir / "p.json", pipeline);
  const std::string html = (dir / "report.html").string();
  test::RunResult r = test::run_cli("run " + (dir / "p.json").string() + " --quiet --report " + (dir / "run.json").string() + " --html " + html, dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The same page from the saved run report.
  r = test::run_cli("report " + (dir / "run.json").string() + " " + (dir / "again.html").string() + " --quiet", dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_GT(std::filesystem::file_size(dir / "again.html"), 500000u);  // three.js and Chart.js inlined

  const std::string script = std::string(POINTSURF_DATA_DIR) + "/../tests/report/browser_check.py";
  const std::string python = std::filesystem::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  const std::string out = (dir / "browser.txt").string();
  const int status = std::system((python + " " + script + " " + html + " --out " + dir.string() + " >" + out + " 2>&1").c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  const std::string said = test::read_bytes(out);
  std::printf("%s", said.c_str());
  if (code == 77) GTEST_SKIP() << said;
  ASSERT_EQ(code, 0) << said;
  // The screenshots it took are real pictures of the view.
  const std::string before = test::read_bytes(dir / "view_before.png");
  const Image shot = decode_png(std::vector<std::uint8_t>(before.begin(), before.end()), "view_before.png");
  EXPECT_GT(shot.width, 300);

  // The check can fail: a console error, and a view that does not move when orbited.
  const std::string page = test::read_bytes(html);
  const std::size_t end = page.rfind("</body>");
  ASSERT_NE(end, std::string::npos);
  const std::pair<const char*, const char*> broken[] = {
      {"<script>console.error('boom');</script>", "console error: boom"},
      {"<script>window.pointsurfView.orbit = function () { return 0; };</script>", "not a live 3D view"}};
  for (const auto& [injected, expected] : broken) {
    test::write_bytes(dir / "broken.html", page.substr(0, end) + injected + page.substr(end));
    const int s = std::system((python + " " + script + " " + (dir / "broken.html").string() + " --out " + dir.string() + " >" + out +
                               " 2>&1").c_str());
    const std::string told = test::read_bytes(out);
    EXPECT_EQ(WIFEXITED(s) ? WEXITSTATUS(s) : -1, 1) << told;
    EXPECT_TRUE(test::contains(told, expected)) << told;
  }
}

}  // namespace
}  // namespace pointsurf
