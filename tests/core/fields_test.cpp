// SPDX-License-Identifier: GPL-3.0-or-later
// Field tables and lengths: a toy Params struct declared once, read, written, validated and
// counted; lengths through text and back.
#include "pointsurf/core/fields.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"

namespace pointsurf {
namespace {

enum class Shape { Plane, Sphere };
const EnumNames<Shape>& shape_names() {
  static const EnumNames<Shape> names{{{Shape::Plane, "plane"}, {Shape::Sphere, "sphere"}}};
  return names;
}

struct ToyParams {
  int k = 16;
  double ratio = 0.5;
  Length radius = Length::spacings(3.0);
  Shape shape = Shape::Plane;
  std::vector<Shape> shapes = {Shape::Plane};
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  bool fast = false;
  std::uint64_t seed = 7;
  static const FieldTable<ToyParams>& fields() {
    static const FieldTable<ToyParams> t = [] {
      FieldTable<ToyParams> t;
      t.integer("k", &ToyParams::k, "Neighbours").at_least(3).when([](const ToyParams& p) { return p.shape == Shape::Plane; });
      t.number("ratio", &ToyParams::ratio, "A share").range(0.0, 1.0, true, false);
      t.length("radius", &ToyParams::radius, "A radius").positive().was("radius_in_spacings");
      t.choice("shape", &ToyParams::shape, shape_names(), "A shape");
      t.choices("shapes", &ToyParams::shapes, shape_names(), "Shapes");
      t.vector3("up", &ToyParams::up, "Up");
      t.boolean("fast", &ToyParams::fast, "Faster").internal();
      t.integer("seed", &ToyParams::seed, "Seed");
      return t;
    }();
    return t;
  }
};

TEST(Length, TextRoundTripsAndResolves) {
  EXPECT_EQ(Length::cloud(0.25).text(), "0.25");
  EXPECT_EQ(Length::spacings(3).text(), "3sp");
  for (const Length l : {Length::cloud(0.1), Length::cloud(1e6 + 0.001), Length::spacings(2.5), Length::spacings(0.1)})
    EXPECT_EQ(Length::parse(l.text(), "r"), l) << l.text();
  EXPECT_EQ(Length::parse("3 sp", "r"), Length::spacings(3));
  EXPECT_EQ(Length::parse("3spacings", "r"), Length::spacings(3));
  EXPECT_DOUBLE_EQ(Length::spacings(3).resolve(0.5), 1.5);
  EXPECT_DOUBLE_EQ(Length::cloud(3).resolve(0.5), 3.0);
  for (const char* bad : {"", "sp", "abc", "3 cm", "nan", "inf", "1e999"})
    test::expect_error<UsageError>([&] { Length::parse(bad, "radius"); }, "radius: \"");
}

TEST(FieldTable, SpecsCarryTheStructsDefaults) {
  const std::vector<ParamSpec> specs = ToyParams::fields().specs();
  ASSERT_EQ(specs.size(), 7u);  // "fast" is internal
  EXPECT_EQ(format_value(specs[0].default_value), "16");
  EXPECT_EQ(format_value(specs[2].default_value), "3sp");
  EXPECT_EQ(specs[2].type, ParamType::Length);
  EXPECT_EQ(format_value(specs[3].default_value), "plane");
  EXPECT_EQ(specs[3].choices, (std::vector<std::string>{"plane", "sphere"}));
  EXPECT_EQ(format_value(specs[4].default_value), "plane");
  EXPECT_EQ(format_value(specs[5].default_value), "0,0,1");
  EXPECT_EQ(specs[6].min, 0.0);  // unsigned
  EXPECT_EQ(specs[2].old_names, std::vector<std::string>{"radius_in_spacings"});
}

TEST(FieldTable, SetAndGetRoundTripEveryType) {
  const FieldTable<ToyParams>& t = ToyParams::fields();
  ToyParams p;
  t.find("k")->set(p, parse_param_text(t.find("k")->spec, "24"));
  t.find("ratio")->set(p, parse_param_text(t.find("ratio")->spec, "0.25"));
  t.find("radius")->set(p, parse_param_text(t.find("radius")->spec, "0.05"));
  t.find("shape")->set(p, parse_param_text(t.find("shape")->spec, "sphere"));
  t.find("shapes")->set(p, parse_param_text(t.find("shapes")->spec, "sphere,plane"));
  t.find("up")->set(p, parse_param_text(t.find("up")->spec, "1,2,3"));
  t.find("seed")->set(p, parse_param_text(t.find("seed")->spec, "99"));
  EXPECT_EQ(p.k, 24);
  EXPECT_EQ(p.ratio, 0.25);
  EXPECT_EQ(p.radius, Length::cloud(0.05));
  EXPECT_EQ(p.shape, Shape::Sphere);
  EXPECT_EQ(p.shapes, (std::vector<Shape>{Shape::Sphere, Shape::Plane}));
  EXPECT_EQ(p.up, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.seed, 99u);
  for (const Field<ToyParams>& f : t) {  // get(set(x)) == x
    ToyParams q;
    f.set(q, f.get(p));
    EXPECT_EQ(format_value(f.get(q)), format_value(f.get(p))) << f.spec.name;
  }
}

TEST(FieldTable, ValidateNamesTheFieldAndHonoursConditions) {
  const FieldTable<ToyParams>& t = ToyParams::fields();
  EXPECT_NO_THROW(t.validate(ToyParams{}, "toy"));
  test::expect_error<UsageError>([&] { t.validate(ToyParams{.k = 2}, "toy"); }, "toy: k must be >= 3, got 2");
  EXPECT_NO_THROW(t.validate(ToyParams{.k = 2, .shape = Shape::Sphere}, "toy"));  // k is for planes only
  test::expect_error<UsageError>([&] { t.validate(ToyParams{.ratio = 0.0}, "toy"); }, "toy: ratio must be in (0, 1], got 0");
  test::expect_error<UsageError>([&] { t.validate(ToyParams{.radius = Length::spacings(-1)}, "toy"); }, "toy: radius must be > 0, got -1sp");
  test::expect_error<UsageError>([&] { parse_param_text(t.find("radius")->spec, "-2"); }, "radius: -2 is out of range (0, inf)");
  test::expect_error<UsageError>([&] { parse_param_text(t.find("shapes")->spec, "plane,cone"); }, "shapes: \"cone\" is not one of plane or sphere");
}

TEST(FieldTable, CountsTheMembersOfAnAggregate) {
  EXPECT_EQ(detail::aggregate_member_count<ToyParams>(), 8u);
  EXPECT_EQ(members_named(ToyParams::fields()), 8u);
}

}  // namespace
}  // namespace pointsurf
