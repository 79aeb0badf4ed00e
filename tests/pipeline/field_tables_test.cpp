// SPDX-License-Identifier: GPL-3.0-or-later
// Every Params struct a stage reads has a field table naming every one of its members, so a
// member added to a struct without its key, unit, range and doc fails here.
#include <gtest/gtest.h>

#include "field_tables.h"

#include "pointsurf/core/fields.h"
#include "pointsurf/features/feature_points.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/pipeline/registry.h"
#include "pointsurf/shape/curvature.h"

namespace pointsurf {
namespace {

TEST(FieldTables, EveryMemberOfEveryStageParamsIsDeclared) {
  test::expect_complete<NormalParams>("NormalParams");
  test::expect_complete<OrientParams>("OrientParams");
  test::expect_complete<CurvatureParams>("CurvatureParams");
  test::expect_complete<FeatureParams>("FeatureParams");
}

// A stage parameter generated from a table shows the table's default, range and doc.
TEST(FieldTables, StageParametersComeFromTheTables) {
  const StageSpec& normals = *find_stage("normals");
  for (const Field<NormalParams>& f : NormalParams::fields()) {
    if (!f.exposed) {
      EXPECT_EQ(normals.find_param(f.spec.name), nullptr) << f.spec.name;
      continue;
    }
    const ParamSpec* p = normals.find_param(f.spec.name);
    ASSERT_NE(p, nullptr) << f.spec.name;
    EXPECT_EQ(format_value(p->default_value), format_value(f.get(NormalParams{})));
    EXPECT_EQ(p->range_text(), f.spec.range_text());
    EXPECT_EQ(p->doc, f.spec.doc);
  }
}

}  // namespace
}  // namespace pointsurf
