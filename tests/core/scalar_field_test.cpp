// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/scalar_field.h"

#include <string>

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

// Regression (found by the sanitizer run): the PLY and XYZ round-trip tests held a reference
// from add() while adding more fields; with the fields in a vector the reference dangled as
// soon as the storage grew. A reference must survive later add() calls.
TEST(FieldSet, ReferencesFromAddSurviveLaterAdds) {
  FieldSet fields;
  ScalarField& first = fields.add("first", 4, ScalarType::UInt8);
  const ScalarField* found = fields.find("first");
  for (int i = 0; i < 40; ++i) fields.add("extra" + std::to_string(i), 4);
  first.values[2] = 7.0;
  ASSERT_EQ(fields.size(), 41u);
  EXPECT_EQ(found, &first);
  EXPECT_EQ(fields.find("first"), &first);
  EXPECT_EQ(fields[0].values[2], 7.0);
  EXPECT_EQ(fields[0].type, ScalarType::UInt8);
}

TEST(FieldSet, AddOfAnExistingNameResizesAndKeepsTheType) {
  FieldSet fields;
  ScalarField& f = fields.add("label", 2, ScalarType::Int16);
  f.values = {3.0, -4.0};
  ScalarField& again = fields.add("label", 3, ScalarType::Float64);
  EXPECT_EQ(&again, &f);
  EXPECT_EQ(again.values, (std::vector<double>{3.0, -4.0, 0.0}));
  EXPECT_EQ(again.type, ScalarType::Int16);
  EXPECT_EQ(fields.size(), 1u);
}

TEST(FieldSet, RemoveKeepsTheOrderOfTheOthers) {
  FieldSet fields;
  for (const char* name : {"a", "b", "c", "d"}) fields.add(name, 1);
  EXPECT_TRUE(fields.remove("b"));
  EXPECT_FALSE(fields.remove("b"));
  ASSERT_EQ(fields.size(), 3u);
  EXPECT_EQ(fields[0].name, "a");
  EXPECT_EQ(fields[1].name, "c");
  EXPECT_EQ(fields[2].name, "d");
  EXPECT_EQ(fields.find("b"), nullptr);
}

}  // namespace
}  // namespace pointsurf
