// SPDX-License-Identifier: GPL-3.0-or-later
// The field tables of the registration stages (register, register-many): every member of their
// Params structs declared, the stage parameters generated from them, and the keys of the
// previous release accepted with a warning.
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/fields.h"
#include "pointsurf/pipeline/registry.h"
#include "pointsurf/register/align.h"
#include "pointsurf/register/features.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/register/multi.h"
#include "pointsurf/register/pose_graph.h"
#include "pointsurf/register/register_pair.h"

#include "field_tables.h"

namespace pointsurf {
namespace {

TEST(FieldTablesRegister, EveryMemberOfEveryRegisterParamsIsDeclared) {
  test::expect_complete<DescriptorParams>("DescriptorParams");
  test::expect_complete<AlignParams>("AlignParams");
  test::expect_complete<IcpParams>("IcpParams");
  test::expect_complete<RegisterPairParams>("RegisterPairParams");
  test::expect_complete<RegisterScansParams>("RegisterScansParams");
  test::expect_complete<PoseGraphParams>("PoseGraphParams");
}

// Both stages show the tables' exposed fields, with their defaults, ranges and docs, and
// nothing the tables keep internal; the keys are unique within a table.
TEST(FieldTablesRegister, StageParametersComeFromTheTables) {
  for (const char* name : {"register", "register-many"}) {
    const StageSpec& stage = *find_stage(name);
    const FieldTable<RegisterScansParams>& table = RegisterScansParams::fields();
    for (const Field<RegisterScansParams>& f : table) {
      const bool many_only = RegisterPairParams::fields().find(f.spec.name) == nullptr;
      const ParamSpec* p = stage.find_param(f.spec.name);
      if (!f.exposed || (many_only && std::string(name) == "register")) {
        EXPECT_EQ(p, nullptr) << name << "." << f.spec.name;
        continue;
      }
      ASSERT_NE(p, nullptr) << name << "." << f.spec.name;
      EXPECT_EQ(format_value(p->default_value), format_value(f.get(RegisterScansParams{}))) << f.spec.name;
      EXPECT_EQ(p->range_text(), f.spec.range_text()) << f.spec.name;
      EXPECT_EQ(p->doc, f.spec.doc) << f.spec.name;
    }
  }
  for (const Field<RegisterScansParams>& f : RegisterScansParams::fields())
    EXPECT_EQ(RegisterScansParams::fields().find(f.spec.name), &f) << "key " << f.spec.name << " twice";
  // ICP iterations: one range for the stage and the library.
  const ParamSpec* iterations = find_stage("register")->find_param("iterations");
  ASSERT_NE(iterations, nullptr);
  EXPECT_EQ(iterations->range_text(), "[1, 100000]");
  IcpParams icp;
  icp.max_iterations = 100001;
  EXPECT_THROW(icp.validate(), UsageError);
}

TEST(FieldTablesRegister, LengthsReplaceTheInSpacingsKeys) {
  const StageSpec& stage = *find_stage("register-many");
  for (const auto& [now, old, value] : {std::tuple{"voxel", "voxel_in_spacings", "2sp"}, std::tuple{"radius", "radius_in_spacings", "10sp"},
                                        std::tuple{"ransac_distance", "ransac_distance_in_spacings", "1.5sp"},
                                        std::tuple{"icp_distance", "icp_distance_in_spacings", "3sp"}}) {
    const ParamSpec* p = stage.find_param(now);
    ASSERT_NE(p, nullptr) << now;
    EXPECT_EQ(p->type, ParamType::Length) << now;
    EXPECT_EQ(format_value(p->default_value), value) << now;
    EXPECT_EQ(p->old_names, std::vector<std::string>{old}) << now;
    EXPECT_EQ(stage.find_param(old), nullptr) << old;
  }
  EXPECT_EQ(RegisterScansParams{}.prune, Length::spacings(0.75));
}

}  // namespace
}  // namespace pointsurf
