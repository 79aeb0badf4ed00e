// SPDX-License-Identifier: GPL-3.0-or-later
// The CLI's progress line (apps/pointsurf/progress_display.h) with an injected clock, and the
// progress trace of a small Poisson run (POINTSURF_PROGRESS_TRACE).
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/io/io.h"
#include "progress_display.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using cli::ProgressDisplay;
using test::contains;

TEST(ProgressDisplay, NothingInTheFirstSecondThenAtLeastEverySecondWithoutNews) {
  ProgressDisplay d("[1/2] reconstruct");
  d.set_fraction(0.1, 0.2);
  EXPECT_FALSE(d.due(0.5));
  EXPECT_TRUE(d.due(1.0));
  // no call arrives: the clock still moves, once a second
  EXPECT_FALSE(d.due(1.5));
  const std::optional<std::string> later = d.due(2.0);
  ASSERT_TRUE(later);
  EXPECT_TRUE(contains(*later, "2.0 s")) << *later;
  EXPECT_FALSE(d.due(2.99));
  EXPECT_TRUE(d.due(3.0));
}

TEST(ProgressDisplay, NewsRedrawsAfterATenthOfASecondNotSooner) {
  ProgressDisplay d("[1/1] normals");
  ASSERT_TRUE(d.due(1.0));
  d.set_fraction(0.5, 1.05);
  EXPECT_FALSE(d.due(1.05));  // 50 ms after the last draw
  EXPECT_TRUE(d.due(1.1));
  d.set_phase("orient");
  EXPECT_TRUE(d.due(1.25));
  d.set_phase("orient");  // the same phase is no news
  EXPECT_FALSE(d.due(1.4));
}

TEST(ProgressDisplay, FinishedShortStageDrawsAtOnce) {
  ProgressDisplay d("[1/1] read");
  d.set_fraction(1.0, 0.1);
  const std::optional<std::string> line = d.due(0.1);
  ASSERT_TRUE(line);
  EXPECT_TRUE(contains(*line, "100%")) << *line;
  EXPECT_TRUE(contains(*line, "done")) << *line;
}

TEST(ProgressDisplay, FractionNeverGoesBackwardsAndIsClamped) {
  ProgressDisplay d("s");
  d.set_fraction(0.6, 1.0);
  d.set_fraction(0.3, 1.1);
  EXPECT_TRUE(contains(d.line(1.2), " 60%")) << d.line(1.2);
  d.set_fraction(7.0, 1.3);
  EXPECT_TRUE(contains(d.line(1.4), "100%")) << d.line(1.4);
}

TEST(ProgressDisplay, LineShowsStagePhaseClockAndTimeLeft) {
  ProgressDisplay d("[2/3] reconstruct");
  d.set_fraction(0.25, 10.0);
  d.set_phase("solve level 7/9");
  const std::string line = d.line(10.0);
  EXPECT_TRUE(contains(line, "[2/3] reconstruct")) << line;
  EXPECT_TRUE(contains(line, " 25%")) << line;
  EXPECT_TRUE(contains(line, "10.0 s")) << line;
  EXPECT_TRUE(contains(line, "~30 s left")) << line;  // a quarter in 10 s: 30 s more
  EXPECT_TRUE(contains(line, "solve level 7/9")) << line;
}

TEST(ProgressDisplay, TimeLeftEstimatesOnlyOnceMeaningful) {
  EXPECT_EQ(ProgressDisplay::time_left_text(0.0, 5.0), "estimating");
  EXPECT_EQ(ProgressDisplay::time_left_text(0.01, 5.0), "estimating");  // under 2 %
  EXPECT_EQ(ProgressDisplay::time_left_text(0.5, 1.0), "estimating");   // under 2 s
  EXPECT_EQ(ProgressDisplay::time_left_text(0.5, 4.0), "~4 s left");
  EXPECT_EQ(ProgressDisplay::time_left_text(0.1, 20.0), "~3 min 00 s left");
  EXPECT_EQ(ProgressDisplay::time_left_text(0.2, 1000.0), "~1 h 06 min left");
  EXPECT_EQ(ProgressDisplay::time_left_text(0.999, 5.0), "~1 s left");
}

TEST(ProgressDisplay, LongPhaseNamesAreShortened) {
  ProgressDisplay d("s");
  d.set_phase(std::string(60, 'x'));
  const std::string line = d.line(1.0);
  EXPECT_TRUE(contains(line, std::string(25, 'x') + "...")) << line;
  EXPECT_FALSE(contains(line, std::string(26, 'x'))) << line;
}

struct TraceLine {
  double seconds = 0.0;
  int index = 0;
  std::string stage, event, value;
};

std::vector<TraceLine> read_trace(const std::filesystem::path& path) {
  std::vector<TraceLine> lines;
  std::ifstream in(path);
  std::string text;
  while (std::getline(in, text)) {
    if (text.empty() || text[0] == '#') continue;
    std::istringstream fields(text);
    TraceLine l;
    std::string seconds, index;
    std::getline(fields, seconds, '\t');
    std::getline(fields, index, '\t');
    std::getline(fields, l.stage, '\t');
    std::getline(fields, l.event, '\t');
    std::getline(fields, l.value);
    l.seconds = std::stod(seconds);
    l.index = std::stoi(index);
    lines.push_back(l);
  }
  return lines;
}

TEST(ProgressTrace, PoissonRunIsMonotoneEndsAtOneAndNamesItsPhases) {
  const std::filesystem::path dir = test::temp_dir("progress_trace_poisson");
  write_point_cloud(dir / "sphere.ply", test::sample_sphere(3000));
  const std::filesystem::path trace = dir / "trace.tsv";
  ::setenv("POINTSURF_PROGRESS_TRACE", trace.c_str(), 1);
  const test::RunResult r =
      test::run_cli("reconstruct " + (dir / "sphere.ply").string() + " " + (dir / "mesh.ply").string() + " --method poisson --depth 6 --quiet", dir);
  ::unsetenv("POINTSURF_PROGRESS_TRACE");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "");  // the trace is no reason to print

  std::vector<double> fractions;
  std::set<std::string> phases;
  bool started = false, ended = false;
  double last_seconds = 0.0;
  for (const TraceLine& l : read_trace(trace)) {
    if (l.stage != "reconstruct") continue;
    EXPECT_GE(l.seconds, last_seconds);
    last_seconds = l.seconds;
    if (l.event == "start") started = true;
    if (l.event == "end") ended = true;
    if (l.event == "fraction") fractions.push_back(std::stod(l.value));
    if (l.event == "phase") phases.insert(l.value);
  }
  EXPECT_TRUE(started);
  EXPECT_TRUE(ended);
  ASSERT_GE(fractions.size(), 10u);
  for (std::size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1]) << "call " << i;
  EXPECT_DOUBLE_EQ(fractions.back(), 1.0);
  for (const char* name : {"octree", "splatting", "extraction"}) EXPECT_TRUE(phases.count(name)) << name;
  bool solve_level = false;
  for (const std::string& name : phases) solve_level = solve_level || name.rfind("solve level ", 0) == 0;
  EXPECT_TRUE(solve_level);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pointsurf
