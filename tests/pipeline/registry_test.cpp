// SPDX-License-Identifier: GPL-3.0-or-later
// The registry: every stage declared once, its --help showing the library's defaults, its
// ranges and choices enforced, "did you mean" on typos.
#include "pointsurf/pipeline/registry.h"

#include <cctype>
#include <map>
#include <regex>
#include <set>

#include <gtest/gtest.h>

#include "cli_run.h"
#include "pointsurf/clean/remove_duplicates.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/clean/smooth_points.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/pipeline.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/features/feature_points.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/shape/curvature.h"
#include "pointsurf/simplify/simplify.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

std::string dashed(const std::string& key) {
  std::string out = "--" + key;
  for (char& c : out)
    if (c == '_') c = '-';
  return out;
}

TEST(Registry, StagesAreUniqueAndEveryParameterIsDocumented) {
  std::set<std::string> names;
  for (const StageSpec& s : registered_stages()) {
    EXPECT_TRUE(names.insert(s.name).second) << s.name;
    EXPECT_FALSE(s.summary.empty()) << s.name;
    EXPECT_TRUE(s.run) << s.name;
    if (!s.methods.empty()) {
      EXPECT_NE(std::find(s.methods.begin(), s.methods.end(), s.default_method), s.methods.end()) << s.name;
    }
    std::set<std::pair<std::string, std::string>> keys;  // (key, method): one declaration each
    for (const ParamSpec& p : s.params) {
      EXPECT_FALSE(p.doc.empty()) << s.name << "." << p.name;
      for (const std::string& m : p.methods) {
        EXPECT_NE(std::find(s.methods.begin(), s.methods.end(), m), s.methods.end()) << s.name << "." << p.name << ": " << m;
        EXPECT_TRUE(keys.insert({p.name, m}).second) << s.name << "." << p.name << " declared twice for " << m;
      }
      if (p.methods.empty()) {
        EXPECT_TRUE(keys.insert({p.name, ""}).second) << s.name << "." << p.name;
      }
      if (p.type == ParamType::Choice && !format_value(p.default_value).empty()) {
        EXPECT_NE(std::find(p.choices.begin(), p.choices.end(), format_value(p.default_value)), p.choices.end()) << s.name << "." << p.name;
      }
    }
  }
  for (const char* stage : {"read", "write", "crop", "range", "merge", "transform", "clean", "simplify", "normals", "curvature", "features",
                            "reconstruct", "quality", "evaluate"})
    EXPECT_NE(find_stage(stage), nullptr) << stage;
}

// The command shape is declared, not inferred; it must agree with what the stage takes and
// gives, since the CLI and Python build the command line from it.
TEST(Registry, EachStagesCommandShapeAgreesWithItsSlots) {
  std::set<CommandShape> seen;
  for (const StageSpec& s : registered_stages()) {
    seen.insert(s.shape);
    const std::size_t n = s.consumes.size();
    switch (s.shape) {
      case CommandShape::Read:
        EXPECT_EQ(n, 0u) << s.name;
        EXPECT_TRUE(s.produces.has_value()) << s.name;
        break;
      case CommandShape::Write:
        EXPECT_EQ(n, 1u) << s.name;
        EXPECT_FALSE(s.produces.has_value()) << s.name;
        break;
      case CommandShape::Transform:
        EXPECT_EQ(n, 1u) << s.name;
        EXPECT_TRUE(s.produces.has_value()) << s.name;
        EXPECT_TRUE(s.writes_param.empty()) << s.name;
        break;
      case CommandShape::Merge:
        ASSERT_EQ(n, 1u) << s.name;
        EXPECT_EQ(s.consumes[0].name, "clouds") << s.name;
        EXPECT_TRUE(s.produces.has_value()) << s.name;
        break;
      case CommandShape::Pair:
        ASSERT_EQ(n, 2u) << s.name;
        EXPECT_EQ(s.consumes[0].name, "source") << s.name;
        EXPECT_EQ(s.consumes[1].name, "target") << s.name;
        break;
      case CommandShape::Compare:
        ASSERT_EQ(n, 2u) << s.name;
        EXPECT_EQ(s.consumes[1].name, "reference") << s.name;
        EXPECT_TRUE(s.measures()) << s.name;
        break;
      case CommandShape::Measure:
        EXPECT_EQ(n, 1u) << s.name;
        EXPECT_TRUE(s.measures()) << s.name;
        break;
      case CommandShape::Picture:
        EXPECT_EQ(n, 1u) << s.name;
        EXPECT_FALSE(s.writes_param.empty()) << s.name;
        break;
    }
    // Only the shapes say "several inputs" and "a measure"; no stage is both.
    EXPECT_EQ(s.takes_many(), s.shape == CommandShape::Merge) << s.name;
    EXPECT_FALSE(s.takes_many() && s.measures()) << s.name;
  }
  for (CommandShape shape : {CommandShape::Read, CommandShape::Write, CommandShape::Transform, CommandShape::Merge, CommandShape::Pair,
                             CommandShape::Compare, CommandShape::Measure, CommandShape::Picture})
    EXPECT_TRUE(seen.count(shape)) << "no stage has shape " << command_shape_name(shape);
}

// A recorded key matches a declared one: equal, or equal but for one "*" standing for one
// path segment each ("deviation_by_region/*/rms", "percentiles/p*").
bool key_matches(const std::string& declared, const std::string& key) {
  std::string pattern;
  for (char c : declared) {
    if (c == '*') pattern += "[^/]+";
    else if (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/') pattern += c;
    else pattern += std::string("\\") + c;
  }
  return std::regex_match(key, std::regex(pattern));
}

bool type_matches(ResultType declared, const ResultValue& v) {
  switch (declared) {
    case ResultType::Integer: return std::holds_alternative<std::int64_t>(v) || std::holds_alternative<double>(v);  // NaN: undefined
    case ResultType::Number: return std::holds_alternative<double>(v);
    case ResultType::Text: return std::holds_alternative<std::string>(v);
    case ResultType::Flag: return std::holds_alternative<bool>(v);
    case ResultType::Numbers: return std::holds_alternative<std::vector<double>>(v);
  }
  return false;
}

// The declaration of `key` in `block` of the stage: the key itself, else the first pattern
// that matches ("outline_area" is not one of the "outline_*").
const ResultSpec* declared(const StageSpec& s, ResultBlock block, const std::string& key) {
  for (const ResultSpec& d : s.results)
    if (d.block == block && d.key == key) return &d;
  for (const ResultSpec& d : s.results)
    if (d.block == block && key_matches(d.key, key)) return &d;
  return nullptr;
}

// Runs `json` and checks that each stage records only keys it declares, in their block and of
// their type; `seen` gathers the declarations each stage's records matched ("counts:points").
void run_and_check(const std::string& json, std::map<std::string, std::set<std::string>>& seen) {
  Context ctx;
  RunReport report;
  ASSERT_NO_THROW(run_pipeline(parse_pipeline(json, "results.json"), ctx, report)) << json;
  ASSERT_TRUE(report.ok) << report.error << "\n" << json;
  for (const StageRecord& r : report.stages) {
    const StageSpec* spec = find_stage(r.type);
    ASSERT_NE(spec, nullptr) << r.type;
    EXPECT_FALSE(spec->results.empty()) << r.type << " declares nothing it reports";
    for (const auto& [block, list] : {std::pair{ResultBlock::Counts, &r.counts}, std::pair{ResultBlock::Metrics, &r.metrics}})
      for (const auto& [key, value] : *list) {
        const ResultSpec* d = declared(*spec, block, key);
        EXPECT_NE(d, nullptr) << r.type << ": " << result_block_name(block) << " \"" << key << "\" is recorded but not declared";
        if (d == nullptr) continue;
        EXPECT_TRUE(type_matches(d->type, value)) << r.type << ": " << key << " is not of its declared type " << result_type_name(d->type);
        seen[r.type].insert(std::string(result_block_name(block)) + ":" + d->key);
      }
  }
}

// Every stage of the registry, each method whose record differs, on small seeded data: a run
// records exactly what its stage declares (counts and metrics, with their types), and each
// declared key shows up in some run (the conditional ones with the option that makes them).
TEST(Registry, EveryStageRecordsExactlyItsDeclaredResults) {
  const std::filesystem::path dir = test::temp_dir("registry_results");
  auto path = [&](const std::string& name) { return (dir / name).string(); };
  PointCloud sphere = test::sample_sphere(1200, 1.0, Vector3d(0.5, -0.2, 0.1), 3);
  ScalarField& segment = sphere.fields.add("segment", sphere.size());
  for (std::size_t i = 0; i < sphere.size(); ++i) segment.values[i] = sphere.positions[i].z() > 0.1 ? 1.0 : 2.0;
  write_point_cloud(path("sphere.ply"), sphere);
  PointCloud zero = sphere;  // one normal without a direction: the stages that use the input's say so
  zero.normals[0] = Vector3d::Zero();
  write_point_cloud(path("zero.ply"), zero);
  PointCloud moved = sphere;
  for (Vector3d& p : moved.positions) p += Vector3d(0.02, -0.01, 0.015);
  write_point_cloud(path("moved.ply"), moved);
  write_point_cloud(path("moved2.ply"), sphere);
  PointCloud cube = test::sample_cube(1500, 1.0, 5);  // planes, edges and corners
  ScalarField& truth = cube.fields.add("truth", cube.size());
  for (std::size_t i = 0; i < cube.size(); ++i) {
    const Vector3d a = cube.positions[i].cwiseAbs();
    truth.values[i] = (a.array() > 0.9).count() >= 2 ? 1.0 : 0.0;  // near an edge
  }
  write_point_cloud(path("cube.ply"), cube);

  std::map<std::string, std::set<std::string>> seen;
  const std::string sphere_ply = "{\"type\": \"read\", \"tag\": \"in\", \"filename\": \"" + path("sphere.ply") + "\"}";
  const std::string cube_ply = "\"" + path("cube.ply") + "\"";
  const std::vector<std::string> runs = {
      // Points: selections, normals of each orientation, curvature with the chosen scale, features
      // scored, segments and outlines, the simplifications, each reconstruction and the measures.
      "[" + cube_ply + ", {\"type\": \"crop\", \"min\": [-5, -5, -5], \"max\": [5, 5, 5]}, {\"type\": \"range\", \"field\": \"z\"},"
      " {\"type\": \"transform\", \"matrix\": [1,0,0,0.1, 0,1,0,0, 0,0,1,0, 0,0,0,1]}, {\"type\": \"normals\"},"
      " {\"type\": \"normals\", \"orient\": \"mst\"}, {\"type\": \"normals\", \"orient\": \"keep\"}, {\"type\": \"curvature\"},"
      " {\"type\": \"features\", \"truth_field\": \"truth\"}, {\"type\": \"boundary\"}, {\"type\": \"segment\"},"
      " {\"type\": \"segment\", \"method\": \"euclidean\"}, {\"type\": \"segment\", \"method\": \"hk\"},"
      " {\"type\": \"segment\", \"method\": \"ransac\"}, {\"type\": \"boundary\"}, \"" + path("points.e57") + "\"]",
      "[\"" + path("zero.ply") + "\", {\"type\": \"curvature\", \"k\": 24}, {\"type\": \"features\", \"normals\": \"input\"},"
      " {\"type\": \"segment\"}, {\"type\": \"clean\", \"method\": \"local,sor,radius,ransac,duplicates,bilateral,trilateral\"}, \"" + path("out.ply") + "\"]",
      "[{\"type\": \"read\", \"filename\": \"" + path("points.e57") + "\", \"keep_poses\": true}, {\"type\": \"range\"}, \"" + path("out.ply") + "\"]",
      "[" + sphere_ply + ", {\"type\": \"simplify\", \"tag\": \"grid\", \"inputs\": \"in\"},"
      " {\"type\": \"simplify\", \"method\": \"random\", \"inputs\": \"in\"},"
      " {\"type\": \"simplify\", \"method\": \"curvature\", \"inputs\": \"in\"},"
      " {\"type\": \"simplify\", \"method\": \"regional\", \"inputs\": \"in\"},"
      " {\"type\": \"simplify\", \"method\": \"curvature-distance\", \"inputs\": \"in\"},"
      " {\"type\": \"simplify\", \"method\": \"lfs\", \"inputs\": \"in\"}, \"" + path("out.ply") + "\"]",
      "[" + sphere_ply + ", {\"type\": \"reconstruct\", \"tag\": \"mesh\"}, \"" + path("mesh.ply") + "\", {\"type\": \"quality\"},"
      " {\"type\": \"evaluate\", \"inputs\": \"mesh\", \"align\": true, \"percentiles\": [50, 99.9]},"
      " {\"type\": \"render\", \"field\": \"deviation\", \"filename\": \"" + path("deviation.png") + "\"}]",
      "[" + sphere_ply + ", {\"type\": \"reconstruct\", \"method\": \"cocone\", \"inputs\": \"in\"},"
      " {\"type\": \"reconstruct\", \"method\": \"crust\", \"inputs\": \"in\"},"
      " {\"type\": \"reconstruct\", \"method\": \"ball-pivot\", \"inputs\": \"in\"},"
      " {\"type\": \"reconstruct\", \"method\": \"poisson\", \"inputs\": \"in\", \"depth\": 5}, \"" + path("out.ply") + "\"]",
      // Two and three clouds.
      "[{\"type\": \"read\", \"filename\": \"" + path("sphere.ply") + "\", \"tag\": \"a\"},"
      " {\"type\": \"read\", \"filename\": \"" + path("moved.ply") + "\", \"tag\": \"b\"},"
      " {\"type\": \"read\", \"filename\": \"" + path("moved2.ply") + "\", \"tag\": \"c\"},"
      " {\"type\": \"merge\", \"inputs\": [\"a\", \"b\"]},"
      " {\"type\": \"register\", \"inputs\": [\"b\", \"a\"], \"ransac_iterations\": 2000},"
      " {\"type\": \"register-many\", \"inputs\": [\"a\", \"b\", \"c\"]}, \"" + path("out.ply") + "\"]",
  };
  for (const std::string& json : runs) run_and_check(json, seen);
  for (const StageSpec& s : registered_stages()) {
    EXPECT_FALSE(s.results.empty()) << s.name << " declares nothing it reports";
    for (const ResultSpec& d : s.results)
      EXPECT_TRUE(seen[s.name].count(std::string(result_block_name(d.block)) + ":" + d.key))
          << s.name << ": declared " << result_block_name(d.block) << " " << d.key << " was not recorded by any run";
  }
  EXPECT_TRUE(key_matches("deviation_by_region/*/rms", "deviation_by_region/segment_1/rms"));
  EXPECT_FALSE(key_matches("deviation_by_region/*/rms", "deviation_by_region/a/b/rms"));
  std::filesystem::remove_all(dir);
}

// StageRecord::add puts each value of a library table in the block its spec says (a nested
// table's values in theirs); add_counts makes every value of a stage's own table a count.
TEST(Registry, AddRecordsEachValueInItsSpecsBlock) {
  SmoothResult r;
  r.moved = 12;
  r.rms_displacement = 0.25;
  r.max_displacement = 0.5;
  r.normals_changed = 3;
  r.mean_normal_change_deg = 4.5;
  StageRecord rec;
  rec.add(SmoothResult::results(true), r, "trilateral.");
  EXPECT_EQ(rec.counts, (ResultList{{"trilateral.moved", std::int64_t{12}}, {"trilateral.normals_changed", std::int64_t{3}}}));
  EXPECT_EQ(rec.metrics, (ResultList{{"trilateral.rms_displacement", 0.25}, {"trilateral.max_displacement", 0.5},
                                     {"trilateral.mean_normal_change_deg", 4.5}}));
  // The declaration says the same blocks.
  std::vector<std::pair<std::string, ResultBlock>> declared;
  for (const ResultSpec& s : prefixed(SmoothResult::results(true).specs(), "trilateral.")) declared.emplace_back(s.key, s.block);
  EXPECT_EQ(declared, (std::vector<std::pair<std::string, ResultBlock>>{{"trilateral.moved", ResultBlock::Counts},
                                                                          {"trilateral.rms_displacement", ResultBlock::Metrics},
                                                                          {"trilateral.max_displacement", ResultBlock::Metrics},
                                                                          {"trilateral.normals_changed", ResultBlock::Counts},
                                                                          {"trilateral.mean_normal_change_deg", ResultBlock::Metrics}}));
  StageRecord all;
  all.add_counts(SmoothResult::results(), r, "bilateral.");
  EXPECT_EQ(all.counts,
            (ResultList{{"bilateral.moved", std::int64_t{12}}, {"bilateral.rms_displacement", 0.25}, {"bilateral.max_displacement", 0.5}}));
  EXPECT_TRUE(all.metrics.empty());
}

// The library's defaults, read from default-constructed Params structs: the registry must
// show exactly these in --help (a default typed a second time would drift).
struct Expected {
  std::string stage, method, key;
  ParamValue value;
};

std::vector<Expected> library_defaults() {
  const NormalParams n;
  using I = std::int64_t;
  return {
      {"curvature", "", "normals_k", I{n.k}},
  };
}

TEST(Registry, HelpShowsEveryDefaultAndTheyAreTheLibrarys) {
  const std::filesystem::path dir = test::temp_dir("registry_help");
  // Walk the registry: every parameter's line in --help carries its default.
  for (const StageSpec& s : registered_stages()) {
    if (s.name == "read" || s.name == "write") continue;
    test::CliResult r = test::run_cli(s.name + " --help", dir);
    ASSERT_EQ(r.exit_code, 0) << s.name << ": " << r.err;
    // Each option's text is wrapped under its column: join the continuation lines.
    for (std::size_t at; (at = r.out.find("\n" + std::string(33, ' '))) != std::string::npos;) r.out.replace(at, 34, " ");
    for (const ParamSpec& p : s.params) {
      const std::string def = format_value(p.default_value);
      if (def.empty()) continue;
      bool found = false;
      std::size_t at = 0;
      while (!found && (at = r.out.find("  " + dashed(p.name) + " ", at)) != std::string::npos) {
        const std::string line = r.out.substr(at, r.out.find('\n', at) - at);
        found = test::contains(line, p.doc) && test::contains(line, "default " + def);
        ++at;
      }
      EXPECT_TRUE(found) << s.name << " --help has no line for " << dashed(p.name) << " with its doc and \"default " << def << "\"";
    }
  }
  // And the registry's defaults are the library's.
  for (const Expected& e : library_defaults()) {
    const StageSpec* s = find_stage(e.stage);
    ASSERT_NE(s, nullptr);
    const ParamSpec* found = nullptr;
    for (const ParamSpec* p : s->params_named(e.key))
      if (p->applies_to(e.method)) found = p;
    ASSERT_NE(found, nullptr) << e.stage << "." << e.key << " (" << e.method << ")";
    EXPECT_EQ(format_value(found->default_value), format_value(e.value)) << e.stage << "." << e.key << " (" << e.method << ")";
  }
  std::filesystem::remove_all(dir);
}

TEST(Registry, RangesAndChoicesAreEnforcedAtTheirBounds) {
  for (const StageSpec& s : registered_stages())
    for (const ParamSpec& p : s.params) {
      if (p.type != ParamType::Int && p.type != ParamType::Double) continue;
      const std::string where = s.name + "." + p.name;
      if (std::isfinite(p.min)) {
        const double outside = p.type == ParamType::Int ? p.min - 1 : p.min_open ? p.min : p.min - 1e-9 * std::max(1.0, std::abs(p.min));
        EXPECT_THROW(parse_param_text(p, format_value(p.type == ParamType::Int ? ParamValue(std::int64_t(outside)) : ParamValue(outside))),
                     UsageError)
            << where;
        if (!p.min_open) {
          EXPECT_NO_THROW(parse_param_text(p, format_value(p.type == ParamType::Int ? ParamValue(std::int64_t(p.min)) : ParamValue(p.min))))
              << where;
        }
      }
      if (std::isfinite(p.max)) {
        const double outside = p.type == ParamType::Int ? p.max + 1 : p.max_open ? p.max : p.max + 1e-9 * std::max(1.0, std::abs(p.max));
        EXPECT_THROW(parse_param_text(p, format_value(p.type == ParamType::Int ? ParamValue(std::int64_t(outside)) : ParamValue(outside))),
                     UsageError)
            << where;
      }
    }
  const ParamSpec& orient = *find_stage("normals")->find_param("orient");
  test::expect_error<UsageError>([&] { parse_param_text(orient, "msst"); }, "orient: \"msst\" is not one of mst, viewpoint, direction, none, input or keep; did you mean \"mst\"?");
  const ParamSpec& k = *find_stage("normals")->find_param("k");
  test::expect_error<UsageError>([&] { parse_param_text(k, "3.5"); }, "k: \"3.5\" is not an integer");
  test::expect_error<UsageError>([&] { parse_param_text(k, "abc"); }, "k: \"abc\" is not an integer");
  EXPECT_EQ(std::get<std::int64_t>(parse_param_text(k, "12")), 12);
  const ParamSpec& viewpoint = *find_stage("normals")->find_param("viewpoint");
  test::expect_error<UsageError>([&] { parse_param_text(viewpoint, "1,2"); }, "viewpoint: \"1,2\": expected 3 numbers X,Y,Z, got 2");
}

TEST(Registry, ClosestNameCatchesTyposOnly) {
  const std::vector<std::string> commands = {"info", "convert", "normals", "curvature", "features", "reconstruct"};
  EXPECT_EQ(closest_name("nromals", commands), "normals");   // a transposition
  EXPECT_EQ(closest_name("normal", commands), "normals");
  EXPECT_EQ(closest_name("reconstrct", commands), "reconstruct");
  EXPECT_EQ(closest_name("kk", {"k", "radius"}), "k");
  EXPECT_EQ(closest_name("poisson", commands), "");
  EXPECT_EQ(closest_name("xyz", {"k"}), "");
}

}  // namespace
}  // namespace pointsurf

namespace pointsurf {
namespace {

// The library's validate() is the one place a value is checked; the registry's declared range
// is what --help shows. Both must agree: a value just outside a declared bound, handed to the
// stage's check (which builds the library's Params and calls validate()), is refused.
TEST(Registry, DeclaredRangesAreTheLibrarysValidate) {
  const std::map<std::string, std::vector<std::string>> validated = {
      {"normals", {""}}, {"curvature", {""}}, {"features", {""}}, {"reconstruct", {"triangulate", "cocone", "crust", "ball-pivot", "poisson"}},
      {"clean", {"local", "sor", "radius", "ransac", "duplicates", "bilateral", "trilateral"}},
      {"simplify", {"curvature", "regional", "curvature-distance", "lfs"}}, {"register", {""}}, {"register-many", {""}}};
  std::size_t checked = 0;
  for (const auto& [stage, methods] : validated) {
    const StageSpec& s = *find_stage(stage);
    for (const std::string& method : methods) {
      auto defaults = [&] {
        std::map<std::string, ParamValue> values;
        for (const ParamSpec& p : s.params)
          if (p.applies_to(method) && !values.count(p.name)) values[p.name] = p.default_value;
        if (!method.empty()) values["method"] = method;
        return values;
      };
      ASSERT_NO_THROW(s.check(StageArgs(defaults(), {}, method))) << stage << " " << method;
      for (const ParamSpec& p : s.params) {
        // normals_k feeds normal estimation, not this stage's Params; a seed is unsigned by its type.
        // ratio, count and cell are checked against the cloud when the stage runs.
        if (p.name == "ratio" || p.name == "count" || p.name == "cell") continue;
        if (!p.applies_to(method) || p.name == "normals_k" || p.name == "seed" ||
            (p.type != ParamType::Int && p.type != ParamType::Double && p.type != ParamType::Length))
          continue;
        for (const bool low : {true, false}) {
          const double bound = low ? p.min : p.max;
          if (!std::isfinite(bound)) continue;
          const bool open = low ? p.min_open : p.max_open;
          const double step = p.type == ParamType::Int ? 1.0 : open ? 0.0 : 1e-6 * std::max(1.0, std::abs(bound));
          const double outside = low ? bound - step : bound + step;
          std::map<std::string, ParamValue> values = defaults();
          values[p.name] = p.type == ParamType::Int      ? ParamValue(static_cast<std::int64_t>(outside))
                           : p.type == ParamType::Length ? ParamValue(Length{outside, std::get<Length>(p.default_value).unit})
                                                         : ParamValue(outside);
          EXPECT_THROW(s.check(StageArgs(values, {{p.name, true}}, method)), UsageError)
              << stage << " " << method << ": " << p.name << " = " << outside << " passes validate() but is outside " << p.range_text();
          ++checked;
        }
      }
    }
  }
  EXPECT_GT(checked, 40u);
}

}  // namespace
}  // namespace pointsurf
