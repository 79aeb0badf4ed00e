// SPDX-License-Identifier: GPL-3.0-or-later
// The field tables of the evaluate and render stages' Params structs name every member.
#include <gtest/gtest.h>

#include "pointsurf/core/fields.h"
#include "pointsurf/evaluate/align_to_mesh.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/pipeline/registry.h"
#include "pointsurf/render/render_scene.h"

#include "field_tables.h"

namespace pointsurf {
namespace {

TEST(FieldTables, EvaluateAndRenderParamsAreComplete) {
  test::expect_complete<MeshDistanceParams>("MeshDistanceParams");
  test::expect_complete<DeviationParams>("DeviationParams");
  test::expect_complete<SurfaceDistanceParams>("SurfaceDistanceParams");
  test::expect_complete<MeshAlignParams>("MeshAlignParams");
  test::expect_complete<RenderParams>("RenderParams");
}

// The evaluate and render stages offer the exposed fields of their tables, with their defaults.
TEST(FieldTables, EvaluateAndRenderParametersComeFromTheTables) {
  const StageSpec& evaluate = *find_stage("evaluate");
  ASSERT_NE(evaluate.find_param("align_max_distance"), nullptr);
  EXPECT_EQ(format_value(evaluate.find_param("align_max_distance")->default_value), "10sp");
  EXPECT_EQ(format_value(evaluate.find_param("sign")->default_value), "auto");
  EXPECT_EQ(evaluate.find_param("sign")->choices, distance_sign_names().names());
  EXPECT_EQ(evaluate.find_param("samples")->min, 1.0);
  for (const char* internal : {"align_samples", "align_seed", "align_relative_rmse", "histogram_min", "exact", "known_self_intersections"})
    EXPECT_EQ(evaluate.find_param(internal), nullptr) << internal;
  const StageSpec& render = *find_stage("render");
  EXPECT_EQ(format_value(render.find_param("size")->default_value), "1024x768");
  EXPECT_EQ(render.find_param("view")->choices, view_names().names());
  EXPECT_EQ(render.find_param("camera"), nullptr);
  EXPECT_EQ(render.find_param("font_file"), nullptr);
}

// A RenderParams read back from its table's text form is the same.
TEST(FieldTables, RenderSizeRoundTrips) {
  RenderParams p;
  const Field<RenderParams>* size = RenderParams::fields().find("size");
  ASSERT_NE(size, nullptr);
  size->set(p, ParamValue(std::string("320x200")));
  EXPECT_EQ(p.size, (PictureSize{320, 200}));
  EXPECT_EQ(format_value(size->get(p)), "320x200");
}

}  // namespace
}  // namespace pointsurf
