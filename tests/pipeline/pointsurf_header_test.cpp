// SPDX-License-Identifier: GPL-3.0-or-later
// The umbrella header compiles on its own, with both curvature parameter structs in one unit
// (what bindings and the pipeline runner need), and the registry takes its defaults from them.
#include "pointsurf/pointsurf.h"

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

const ParamSpec& param(const std::string& stage, const std::string& key, const std::string& method) {
  const StageSpec* s = find_stage(stage);
  EXPECT_NE(s, nullptr) << stage;
  for (const ParamSpec* p : s->params_named(key))
    if (p->applies_to(method)) return *p;
  ADD_FAILURE() << stage << "." << key << " for " << method;
  static const ParamSpec none;
  return none;
}

TEST(PointsurfHeader, BothCurvatureParamsLiveTogetherAndFeedTheRegistry) {
  const CurvatureParams shape;              // shape/curvature.h: jet fitting
  const CurvatureSimplifyParams simplify;   // simplify/simplify.h: curvature-weighted sampling
  EXPECT_EQ(std::get<std::int64_t>(param("curvature", "k", "").default_value), shape.k);
  EXPECT_EQ(std::get<std::int64_t>(param("curvature", "degree", "").default_value), shape.degree);
  // The drift the review found (the CLI typed 16 for simplify --method curvature): now one value.
  EXPECT_EQ(std::get<std::int64_t>(param("simplify", "k", "curvature").default_value), simplify.k);
  EXPECT_EQ(simplify.k, 20);
  EXPECT_EQ(std::get<std::int64_t>(param("simplify", "k", "regional").default_value), RegionalParams{}.k);
}

}  // namespace
}  // namespace pointsurf
