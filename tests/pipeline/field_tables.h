// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The completeness check of a field table (core/fields.h), shared by the field_tables*_test.cpp
// files: every member of P is named by a field, every field is documented, reads and writes
// its member, and P's defaults pass P's own validate().
#include <gtest/gtest.h>

#include "pointsurf/core/fields.h"

namespace pointsurf::test {

template <class P>
void expect_complete(const char* name) {
  const FieldTable<P>& table = P::fields();
  EXPECT_EQ(members_named(table), detail::aggregate_member_count<P>()) << name << ": a member has no field in its table";
  for (const Field<P>& f : table) {
    EXPECT_FALSE(f.spec.doc.empty()) << name << "." << f.spec.name;
    EXPECT_TRUE(f.get && f.set) << name << "." << f.spec.name;
    // The struct's default passes the field's own range where the field applies.
    if (!f.applies || f.applies(P{})) {
      EXPECT_EQ(range_failure(f.spec, f.get(P{})), "") << name << "." << f.spec.name;
    }
    P round_trip;  // set(get(default)) keeps the value
    f.set(round_trip, f.get(P{}));
    EXPECT_EQ(format_value(f.get(round_trip)), format_value(f.get(P{}))) << name << "." << f.spec.name;
  }
  EXPECT_NO_THROW(P{}.validate()) << name;
}

}  // namespace pointsurf::test
