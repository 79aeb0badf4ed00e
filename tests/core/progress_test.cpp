// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/progress.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

// A whole that records what it hears.
struct Heard {
  std::vector<double> fractions;
  std::vector<std::string> phases;
  std::vector<ProgressForecast> forecasts;
  ProgressCallback callback() {
    PhasedProgress p;
    p.on_fraction = [this](double f) {
      fractions.push_back(f);
      return true;
    };
    p.on_phase = [this](std::string_view name) { phases.emplace_back(name); };
    p.on_forecast = [this](const ProgressForecast& f) { forecasts.push_back(f); };
    return p;
  }
};

TEST(Progress, SubProgressMapsFractionsPassesPhasesButNotForecasts) {
  Heard heard;
  const ProgressCallback whole = heard.callback();
  const ProgressCallback part = sub_progress(whole, 0.2, 0.6, "part");
  ASSERT_TRUE(part(0.5));
  report_phase(part, "inner");
  report_forecast(part, {3.0, 100.0});
  ASSERT_EQ(heard.fractions.size(), 1u);
  EXPECT_DOUBLE_EQ(heard.fractions[0], 0.4);
  EXPECT_EQ(heard.phases, (std::vector<std::string>{"part", "inner"}));
  EXPECT_TRUE(heard.forecasts.empty());  // a forecast describes the callee's whole run
  report_forecast(whole, {3.0, 100.0});
  ASSERT_EQ(heard.forecasts.size(), 1u);
  EXPECT_DOUBLE_EQ(heard.forecasts[0].seconds, 3.0);
  EXPECT_DOUBLE_EQ(heard.forecasts[0].output_size, 100.0);
  // a plain callback hears neither phases nor forecasts, and nothing breaks
  const ProgressCallback plain = [](double) { return true; };
  report_phase(plain, "x");
  report_forecast(plain, {1.0, 1.0});
  EXPECT_FALSE(sub_progress(ProgressCallback{}, 0.0, 1.0));
}

// Moving the end keeps what was reported and stretches the rest from the last fraction heard:
// continuous, never backwards, and the part's end lands where it was moved.
TEST(Progress, MovableProgressStretchesTheRestContinuously) {
  Heard heard;
  MovableProgress part(heard.callback(), 0.1, 0.5);
  const ProgressCallback cb = part.callback();
  ASSERT_TRUE(cb(0.5));
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.3);
  part.move_end(0.9);  // more work than assumed: the remaining half of the part now spans 0.3..0.9
  EXPECT_DOUBLE_EQ(part.end(), 0.9);
  cb(0.5);
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.3);
  cb(0.75);
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.6);
  part.move_end(0.2);  // below what was reported: held there, never backwards
  EXPECT_DOUBLE_EQ(part.end(), 0.6);
  cb(0.9);
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.6);
  cb(1.0);
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.6);
  cb(0.1);  // a late, smaller fraction does not go back
  EXPECT_DOUBLE_EQ(heard.fractions.back(), 0.6);
  for (std::size_t i = 1; i < heard.fractions.size(); ++i) EXPECT_GE(heard.fractions[i], heard.fractions[i - 1]);
}

TEST(Progress, MovableProgressForwardsPhasesForecastsAndCancellation) {
  Heard heard;
  bool stop = false;
  PhasedProgress whole;
  whole.on_fraction = [&](double f) {
    heard.fractions.push_back(f);
    return !stop;
  };
  whole.on_phase = [&](std::string_view name) { heard.phases.emplace_back(name); };
  MovableProgress part(whole, 0.0, 1.0);
  double forecast = 0.0;
  const ProgressCallback cb = part.callback([&](const ProgressForecast& f) { forecast = f.seconds; });
  report_phase(cb, "solve");
  report_forecast(cb, {7.5, 0.0});
  EXPECT_EQ(heard.phases, (std::vector<std::string>{"solve"}));
  EXPECT_DOUBLE_EQ(forecast, 7.5);
  EXPECT_TRUE(cb(0.2));
  stop = true;
  EXPECT_FALSE(cb(0.3));
  EXPECT_FALSE(MovableProgress(ProgressCallback{}, 0.0, 1.0).callback());
}

}  // namespace
}  // namespace pointsurf
