// SPDX-License-Identifier: GPL-3.0-or-later
// The field tables of the segment, boundary and reconstruct stages' Params: every member named,
// documented, its default within its own range; and the stages' parameters generated from them.
#include <gtest/gtest.h>

#include "field_tables.h"
#include "pointsurf/core/fields.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/pipeline/registry.h"
#include "pointsurf/reconstruct/ball_pivot.h"
#include "pointsurf/reconstruct/cocone.h"
#include "pointsurf/reconstruct/crust.h"
#include "pointsurf/reconstruct/delaunay_surface.h"
#include "pointsurf/reconstruct/fill_holes.h"
#include "pointsurf/reconstruct/flat_regions.h"
#include "pointsurf/reconstruct/mesh_cleanup.h"
#include "pointsurf/reconstruct/poisson.h"
#include "pointsurf/reconstruct/triangulate.h"
#include "pointsurf/segment/outlines.h"
#include "pointsurf/segment/segment.h"
#include "pointsurf/shape/primitives.h"

namespace pointsurf {
namespace {

// The Delaunay methods' structs derive from DelaunaySurfaceParams, whose members an aggregate
// count sees as one: test::expect_complete with the count of `members` given.
template <class P>
void expect_table(const char* name, std::size_t members) {
  const FieldTable<P>& table = P::fields();
  EXPECT_EQ(members_named(table), members) << name << ": a member has no field in its table";
  for (const Field<P>& f : table) {
    EXPECT_FALSE(f.spec.doc.empty()) << name << "." << f.spec.name;
    EXPECT_TRUE(f.get && f.set) << name << "." << f.spec.name;
    if (!f.applies || f.applies(P{})) {
      EXPECT_EQ(range_failure(f.spec, f.get(P{})), "") << name << "." << f.spec.name;
    }
    P q;  // set(get(default)) keeps the value
    f.set(q, f.get(P{}));
    EXPECT_EQ(format_value(f.get(q)), format_value(f.get(P{}))) << name << "." << f.spec.name;
  }
}

TEST(FieldTablesRecon, EveryMemberOfEveryStageParamsIsDeclared) {
  test::expect_complete<RegionGrowingParams>("RegionGrowingParams");
  test::expect_complete<EuclideanParams>("EuclideanParams");
  test::expect_complete<SurfaceTypeParams>("SurfaceTypeParams");
  test::expect_complete<PrimitiveParams>("PrimitiveParams");
  test::expect_complete<BoundaryParams>("BoundaryParams");
  test::expect_complete<OutlineParams>("OutlineParams");
  test::expect_complete<TriangulateParams>("TriangulateParams");
  test::expect_complete<BallPivotParams>("BallPivotParams");
  test::expect_complete<PoissonParams>("PoissonParams");
  test::expect_complete<HoleFillParams>("HoleFillParams");
  test::expect_complete<SmallComponentParams>("SmallComponentParams");
  test::expect_complete<FlatRegionParams>("FlatRegionParams");
  // The Delaunay methods: their base's fields, then their own.
  const std::size_t base = detail::aggregate_member_count<DelaunaySurfaceParams>();
  expect_table<DelaunaySurfaceParams>("DelaunaySurfaceParams", base);
  EXPECT_NO_THROW(DelaunaySurfaceParams{}.validate("test"));
  expect_table<CoconeParams>("CoconeParams", base + detail::aggregate_member_count<CoconeParams>() - 1);
  EXPECT_NO_THROW(CoconeParams{}.validate());
  expect_table<CrustParams>("CrustParams", base + detail::aggregate_member_count<CrustParams>() - 1);
  EXPECT_NO_THROW(CrustParams{}.validate());
}

TEST(FieldTablesRecon, LengthsAndListsRoundTrip) {
  PrimitiveParams p;
  const FieldTable<PrimitiveParams>& t = PrimitiveParams::fields();
  EXPECT_EQ(format_value(t.find("types")->get(p)), "plane,sphere,cylinder,cone");
  EXPECT_EQ(format_value(t.find("epsilon")->get(p)), "1sp");
  EXPECT_EQ(format_value(t.find("cluster_epsilon")->get(p)), "3sp");
  t.find("types")->set(p, parse_param_text(t.find("types")->spec, "torus,plane"));
  EXPECT_EQ(p.types, (std::vector<PrimitiveType>{PrimitiveType::Torus, PrimitiveType::Plane}));
  EXPECT_EQ(primitive_mask(p.types), unsigned(kTori | kPlanes));
  EXPECT_EQ(t.find("max_normal_angle_deg")->spec.old_names, std::vector<std::string>{"max_normal_deg"});
  EXPECT_EQ(PoissonParams::fields().find("weight_by_normal_length")->spec.old_names, std::vector<std::string>{"confidence"});
  EXPECT_EQ(format_value(TriangulateParams::fields().find("radius")->get(TriangulateParams{})), "3sp");
  EXPECT_EQ(format_value(OutlineParams::fields().find("alpha")->get(OutlineParams{})), "5sp");
  EXPECT_EQ(format_value(EuclideanParams::fields().find("radius")->get(EuclideanParams{})), "3sp");
}

// The stages' parameters carry the tables' defaults, ranges and docs, per method.
template <class P>
void expect_stage_has(const StageSpec& stage, const std::string& method) {
  for (const Field<P>& f : P::fields()) {
    if (!f.exposed) continue;
    const ParamSpec* found = nullptr;
    for (const ParamSpec& p : stage.params)
      if (p.name == f.spec.name && (method.empty() || p.applies_to(method))) found = found ? found : &p;
    ASSERT_NE(found, nullptr) << stage.name << " " << method << ": " << f.spec.name;
    EXPECT_EQ(format_value(found->default_value), format_value(f.get(P{}))) << f.spec.name;
    EXPECT_EQ(found->range_text(), f.spec.range_text()) << f.spec.name;
    EXPECT_EQ(found->doc, f.spec.doc) << f.spec.name;
  }
}

TEST(FieldTablesRecon, StageParametersComeFromTheTables) {
  const StageSpec& segment = *find_stage("segment");
  expect_stage_has<RegionGrowingParams>(segment, "region");
  expect_stage_has<EuclideanParams>(segment, "euclidean");
  expect_stage_has<SurfaceTypeParams>(segment, "hk");
  expect_stage_has<PrimitiveParams>(segment, "ransac");
  const StageSpec& boundary = *find_stage("boundary");
  expect_stage_has<BoundaryParams>(boundary, "");
  expect_stage_has<OutlineParams>(boundary, "");
  const StageSpec& reconstruct = *find_stage("reconstruct");
  expect_stage_has<TriangulateParams>(reconstruct, "triangulate");
  expect_stage_has<CoconeParams>(reconstruct, "cocone");
  expect_stage_has<CrustParams>(reconstruct, "crust");
  expect_stage_has<BallPivotParams>(reconstruct, "ball-pivot");
  expect_stage_has<PoissonParams>(reconstruct, "poisson");
  for (const char* method : {"triangulate", "cocone", "crust", "ball-pivot", "poisson"}) {
    expect_stage_has<SmallComponentParams>(reconstruct, method);
    expect_stage_has<FlatRegionParams>(reconstruct, method);
  }
  EXPECT_EQ(reconstruct.find_param("tolerance"), nullptr);  // internal
}

}  // namespace
}  // namespace pointsurf
