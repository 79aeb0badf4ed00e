// SPDX-License-Identifier: GPL-3.0-or-later
// Result tables: members are emitted once each, in declaration order, under the caller's
// prefix, with nested blocks and families expanded, each in the report's block its spec says,
// and the specs say what each key is.
#include "pointsurf/core/results.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

namespace pointsurf {
namespace {

struct Inner {
  double lo = 0.0, hi = 0.0;
  static const ResultTable<Inner>& results() {
    static const ResultTable<Inner> t = [] {
      ResultTable<Inner> t;
      t.number("lo", &Inner::lo, "Low");
      t.number("hi", &Inner::hi, "High");
      return t;
    }();
    return t;
  }
};

struct Fit {
  std::size_t inliers = 0;
  double rms = 0.0;
  bool converged = false;
  std::string message;
  std::vector<std::size_t> histogram;
  std::vector<double> ranks, values;
  Inner range;
  static const ResultTable<Fit>& results() {
    static const ResultTable<Fit> t = [] {
      ResultTable<Fit> t;
      t.count("inliers", &Fit::inliers, "Inliers").higher_is_better();
      t.number("rms", &Fit::rms, "RMS").with_unit("cloud units").lower_is_better();
      t.flag("converged", &Fit::converged, "Converged");
      t.text("message", &Fit::message, "How it ended");
      t.numbers("histogram", &Fit::histogram, "Counts per bin");
      t.family(
          "p*", ResultType::Number,
          [](const Fit& f) {
            std::vector<std::pair<std::string, ResultValue>> out;
            for (std::size_t i = 0; i < f.ranks.size(); ++i) out.emplace_back(std::to_string(static_cast<int>(f.ranks[i])), f.values[i]);
            return out;
          },
          "Percentiles");
      t.nested("range/", &Fit::range, Inner::results());
      t.computed("span", ResultType::Number, [](const Fit& f) { return ResultValue(f.range.hi - f.range.lo); }, "hi - lo");
      return t;
    }();
    return t;
  }
};

TEST(ResultTable, EmitsEveryMemberOnceInOrderUnderThePrefix) {
  Fit f;
  f.inliers = 42;
  f.rms = 0.25;
  f.converged = true;
  f.message = "ok";
  f.histogram = {1, 2, 3};
  f.ranks = {50, 95};
  f.values = {0.1, 0.9};
  f.range = {-1.0, 3.0};
  ResultList got;
  Fit::results().record(f, [&](std::string key, ResultValue v) { got.emplace_back(std::move(key), std::move(v)); }, "fit/");
  const std::vector<std::string> keys = {"fit/inliers", "fit/rms", "fit/converged", "fit/message", "fit/histogram", "fit/p50",
                                         "fit/p95",     "fit/range/lo", "fit/range/hi", "fit/span"};
  ASSERT_EQ(got.size(), keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(got[i].first, keys[i]) << i;
  EXPECT_EQ(std::get<std::int64_t>(got[0].second), 42);
  EXPECT_EQ(std::get<double>(got[1].second), 0.25);
  EXPECT_TRUE(std::get<bool>(got[2].second));
  EXPECT_EQ(std::get<std::string>(got[3].second), "ok");
  EXPECT_EQ(std::get<std::vector<double>>(got[4].second), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(std::get<double>(got[6].second), 0.9);
  EXPECT_EQ(std::get<double>(got[8].second), 3.0);
  EXPECT_EQ(std::get<double>(got[9].second), 4.0);
}

TEST(ResultTable, SpecsNameEveryKeyWithItsTypeUnitAndDirection) {
  const std::vector<ResultSpec>& s = Fit::results().specs();
  std::vector<std::string> keys;
  for (const ResultSpec& r : s) keys.push_back(r.key);
  EXPECT_EQ(keys, (std::vector<std::string>{"inliers", "rms", "converged", "message", "histogram", "p*", "range/lo", "range/hi", "span"}));
  EXPECT_EQ(s[0].type, ResultType::Integer);
  EXPECT_EQ(s[0].better, Better::Higher);
  EXPECT_EQ(s[1].unit, "cloud units");
  EXPECT_EQ(s[1].better, Better::Lower);
  EXPECT_STREQ(better_name(s[1].better), "lower");
  EXPECT_STREQ(result_type_name(s[4].type), "numbers");
  const std::vector<ResultSpec> p = prefixed(s, "fit/");
  EXPECT_EQ(p[6].key, "fit/range/lo");
}

TEST(ResultTable, CountedSpecsAreCountsAndTheRestMetrics) {
  const std::vector<ResultSpec>& s = Fit::results().specs();
  std::vector<ResultSpec> declared = counted(s, "fit.");
  ASSERT_EQ(declared.size(), s.size());
  EXPECT_EQ(declared[0].key, "fit.inliers");
  EXPECT_STREQ(result_block_name(declared[0].block), "counts");
  append(declared, s);  // as metrics: the default block
  ASSERT_EQ(declared.size(), 2 * s.size());
  EXPECT_EQ(declared[s.size()].key, "inliers");
  EXPECT_STREQ(result_block_name(declared[s.size()].block), "metrics");
  EXPECT_FALSE(s[0].headline);
  ResultSpec h;
  EXPECT_TRUE(h.in_headline().headline);
}

TEST(ResultTable, AnEmptyFamilyEmitsNothing) {
  const Fit f;
  std::vector<std::string> keys;
  Fit::results().record(f, [&](std::string key, ResultValue) { keys.push_back(std::move(key)); });
  EXPECT_EQ(std::count_if(keys.begin(), keys.end(), [](const std::string& k) { return k[0] == 'p'; }), 0);
  EXPECT_EQ(keys.size(), 8u);
}


// A table marking its counts: the spec says the block, and a nested table's values keep theirs.
struct Sizes {
  std::size_t points = 0;
  double spacing = 0.0;
  static const ResultTable<Sizes>& results() {
    static const ResultTable<Sizes> t = [] {
      ResultTable<Sizes> t;
      t.count("points", &Sizes::points, "Points").as_count();
      t.number("spacing", &Sizes::spacing, "Spacing");
      return t;
    }();
    return t;
  }
};
struct Solve {
  std::size_t faces = 0, iterations = 0;
  Sizes input;
  static const ResultTable<Solve>& results() {
    static const ResultTable<Solve> t = [] {
      ResultTable<Solve> t;
      t.count("faces", &Solve::faces, "Faces").as_count();
      t.nested("input/", &Solve::input, Sizes::results());
      t.count("iterations", &Solve::iterations, "Iterations");  // an integer, but a metric
      return t;
    }();
    return t;
  }
};

TEST(ResultTable, EachValueGoesToTheBlockItsSpecSays) {
  Solve run;
  run.faces = 7;
  run.iterations = 3;
  run.input = {100, 0.5};
  std::vector<std::pair<ResultBlock, std::string>> got;
  ResultList values;
  Solve::results().record_blocks(run, [&](ResultBlock b, std::string key, ResultValue v) {
    got.emplace_back(b, key);
    values.emplace_back(std::move(key), std::move(v));
  }, "run/");
  const std::vector<std::pair<ResultBlock, std::string>> expected = {{ResultBlock::Counts, "run/faces"},
                                                                     {ResultBlock::Counts, "run/input/points"},
                                                                     {ResultBlock::Metrics, "run/input/spacing"},
                                                                     {ResultBlock::Metrics, "run/iterations"}};
  EXPECT_EQ(got, expected);
  ASSERT_EQ(values.size(), 4u);
  EXPECT_EQ(std::get<std::int64_t>(values[0].second), 7);
  EXPECT_EQ(std::get<std::int64_t>(values[1].second), 100);
  EXPECT_EQ(std::get<double>(values[2].second), 0.5);
  EXPECT_EQ(std::get<std::int64_t>(values[3].second), 3);
  // The plain record emits the same values in the same order.
  ResultList plain;
  Solve::results().record(run, [&](std::string key, ResultValue v) { plain.emplace_back(std::move(key), std::move(v)); }, "run/");
  EXPECT_EQ(plain, values);
}

TEST(ResultTable, SpecsCarryTheBlocksTheTableMarks) {
  const std::vector<ResultSpec>& s = Solve::results().specs();
  std::vector<std::pair<std::string, ResultBlock>> got;
  for (const ResultSpec& r : s) got.emplace_back(r.key, r.block);
  const std::vector<std::pair<std::string, ResultBlock>> expected = {{"faces", ResultBlock::Counts},
                                                                     {"input/points", ResultBlock::Counts},
                                                                     {"input/spacing", ResultBlock::Metrics},
                                                                     {"iterations", ResultBlock::Metrics}};
  EXPECT_EQ(got, expected);
  // prefixed() keeps each block; counted() makes every one a count.
  const std::vector<ResultSpec> p = prefixed(s, "run/");
  EXPECT_EQ(p[1].key, "run/input/points");
  EXPECT_EQ(p[1].block, ResultBlock::Counts);
  EXPECT_EQ(p[2].block, ResultBlock::Metrics);
  for (const ResultSpec& r : counted(s)) EXPECT_EQ(r.block, ResultBlock::Counts) << r.key;
  EXPECT_EQ(Fit::results().specs()[0].block, ResultBlock::Metrics);  // count() alone says nothing of the block
}

}  // namespace
}  // namespace pointsurf
