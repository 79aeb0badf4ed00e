// SPDX-License-Identifier: GPL-3.0-or-later
// `pointsurf run`: a corpus of malformed pipelines, each failing before any work with its named
// error and no output; and every registered stage giving the same bytes as a CLI command and
// as a one-stage pipeline (and whatever the thread count).
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/registry.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class RunCli : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("run_cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    PointCloud sphere = test::sample_sphere(3000, 1.0, Vector3d(2, 0, 1));
    write_point_cloud(path("in.ply"), sphere);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write_pipeline(const std::string& name, const std::string& text) const {
    test::write_bytes(dir_ / name, text);
    return path(name);
  }
  std::filesystem::path dir_;
};

struct Malformed {
  std::string name, json, sets, message;
  int exit_code = 1;
};

TEST_F(RunCli, MalformedPipelinesFailBeforeAnyWorkNamingStageAndKey) {
  const std::string in = "\"" + path("in.ply") + "\"", out = "\"" + path("out.ply") + "\"";
  const std::vector<Malformed> corpus = {
      {"not_json", "[" + in + ", {\"type\": \"normals\",}]", "", "not_json.json: not valid JSON at line 1"},
      {"not_a_list", "{\"type\": \"normals\"}", "", "not_a_list.json: a pipeline is a JSON list of stages"},
      {"empty", "[]", "", "empty.json: the pipeline is empty"},
      {"unknown_stage", "[" + in + ", {\"type\": \"nromals\"}, " + out + "]", "",
       "unknown_stage.json: stage 2 (nromals): unknown stage type \"nromals\"; did you mean \"normals\"?"},
      {"unknown_key", "[" + in + ", {\"type\": \"clean\"}, {\"type\": \"normals\", \"kk\": 3}, " + out + "]", "",
       "unknown_key.json: stage 3 (normals): unknown key \"kk\"; did you mean \"k\"?"},
      {"wrong_type", "[" + in + ", {\"type\": \"normals\", \"k\": \"thirty\"}, " + out + "]", "",
       "wrong_type.json: stage 2 (normals): k: expected an integer, got a string"},
      {"fraction_for_integer", "[" + in + ", {\"type\": \"normals\", \"k\": 2.5}, " + out + "]", "",
       "stage 2 (normals): k: expected an integer, got a number"},
      {"out_of_range", "[" + in + ", {\"type\": \"normals\", \"k\": 2}, " + out + "]", "", "stage 2 (normals): k: 2 is out of range [3, inf)"},
      {"bad_choice", "[" + in + ", {\"type\": \"normals\", \"orient\": \"sideways\"}, " + out + "]", "",
       "stage 2 (normals): orient: \"sideways\" is not one of mst, viewpoint, direction, none, input or keep"},
      {"other_method", "[" + in + ", {\"type\": \"simplify\", \"method\": \"grid\", \"region_angle_deg\": 20}, " + out + "]", "",
       "stage 2 (simplify): region_angle_deg belongs to method regional, not to method grid"},
      {"ignored_option", "[" + in + ", {\"type\": \"normals\", \"viewpoint\": [0, 0, 5]}, " + out + "]", "",
       "stage 2 (normals): viewpoint: ignored unless orient is viewpoint"},
      {"missing_input", "[" + in + ", {\"type\": \"normals\", \"inputs\": \"scan\"}, " + out + "]", "",
       "stage 2 (normals): input \"scan\" is not the tag of an earlier stage"},
      {"writer_first", "[{\"type\": \"write\", \"filename\": " + out + "}, " + in + "]", "", "stage 1 (write): a writer before any data"},
      {"stage_first", "[{\"type\": \"normals\"}, " + out + "]", "", "stage 1 (normals): a stage before any data"},
      {"no_output", "[" + in + ", {\"type\": \"normals\"}]", "", "no_output.json: no output: end the pipeline with a file name to write"},
      {"missing_type", "[" + in + ", {\"k\": 3}, " + out + "]", "", "stage 2: missing \"type\""},
      {"tag_twice", "[" + in + ", {\"type\": \"normals\", \"tag\": \"a\"}, {\"type\": \"clean\", \"tag\": \"a\"}, " + out + "]", "",
       "stage 3 (clean): tag \"a\" is used twice"},
      {"bad_extension", "[" + in + ", {\"type\": \"normals\"}, \"" + path("out.xyzw") + "\"]", "", "unknown output format"},
      {"missing_directory", "[" + in + ", {\"type\": \"normals\"}, \"" + path("nowhere/out.ply") + "\"]", "", "does not exist"},
      {"not_rigid", "[" + in + ", {\"type\": \"transform\", \"matrix\": [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}, " + out + "]", "",
       "stage 2 (transform): matrix: the upper-left 3x3 block is not a rotation"},
      {"set_unknown_stage", "[" + in + ", {\"type\": \"normals\"}, " + out + "]", "--set nromals.k=12",
       "--set \"nromals.k=12\": no stage tagged or typed \"nromals\"; did you mean \"normals\"?"},
      {"set_type_error", "[" + in + ", {\"type\": \"normals\"}, " + out + "]", "--set normals.k=abc", "stage 2 (normals): k: \"abc\" is not an integer"},
      {"reader_with_inputs", "[" + in + ", {\"type\": \"read\", \"filename\": " + in + ", \"inputs\": \"read1\"}, " + out + "]", "",
       "stage 2 (read): takes no \"inputs\""},
      {"written_twice", "[" + in + ", {\"type\": \"normals\"}, " + out + ", {\"type\": \"clean\"}, " + out + "]", "", "out.ply is written twice"},
      {"missing_file", "[\"" + path("no_such.ply") + "\", {\"type\": \"normals\"}, " + out + "]", "", "no_such.ply: no such file", 2},
  };
  ASSERT_GE(corpus.size(), 15u);
  for (const Malformed& m : corpus) {
    const std::string file = write_pipeline(m.name + ".json", m.json);
    const test::CliResult r = test::run_cli("run " + file + " " + m.sets + " --report " + path("r.json"), dir_);
    EXPECT_EQ(r.exit_code, m.exit_code) << m.name << ": " << r.err;
    EXPECT_TRUE(test::contains(r.err, m.message)) << m.name << ": " << r.err << "\nexpected: " << m.message;
    EXPECT_FALSE(std::filesystem::exists(path("out.ply"))) << m.name;
    EXPECT_FALSE(std::filesystem::exists(path("out.xyzw"))) << m.name;
  }
}

TEST_F(RunCli, RunWritesOneReportWithASummaryLinePerStage) {
  const std::string file = write_pipeline("p.json", "[\"" + path("in.ply") + "\", {\"type\": \"clean\", \"method\": \"sor,duplicates\"}, " +
                                                        "{\"type\": \"normals\", \"k\": 20}, {\"type\": \"reconstruct\"}, \"" + path("m.ply") + "\"]");
  const test::CliResult r = test::run_cli("run " + file + " --set normals.k=16 --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* line : {"[1/5] read 3000 points", "[2/5] clean: 3000 points ->", "[3/5] normals:", "[4/5] reconstruct: triangulate",
                           "[5/5] wrote "})
    EXPECT_TRUE(test::contains(r.err, line)) << line << "\n" << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["command"], "run");
  ASSERT_EQ(report["stages"].size(), 5u);
  EXPECT_EQ(report["stages"][2]["parameters"]["k"], 16);  // the --set value is the one used
  EXPECT_EQ(report["stages"][1]["parameters"]["sor.k"], 20);
  EXPECT_EQ(report["stages"][1]["parameters"]["method"], "sor,duplicates");
}

// Extra options a stage needs on the test sphere (the others run with their defaults).
std::string options_for(const std::string& stage, bool json) {
  if (stage == "crop") return json ? "\"min\": [1.5, -2, 0], \"max\": [3, 2, 3]" : "--min 1.5,-2,0 --max 3,2,3";
  if (stage == "range") return json ? "\"field\": \"x\", \"min\": 2, \"max\": 5" : "--field x --min 2 --max 5";
  if (stage == "transform")
    return json ? "\"matrix\": [0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]" : "--matrix 0,-1,0,1,1,0,0,2,0,0,1,3,0,0,0,1";
  if (stage == "simplify") return json ? "\"method\": \"regional\", \"ratio\": 0.3" : "--method regional --ratio 0.3";
  if (stage == "clean") return json ? "\"method\": \"sor,duplicates\"" : "--method sor,duplicates";
  return "";
}

TEST_F(RunCli, EveryStageGivesTheSameBytesAsCommandAndAsPipelineWhateverTheThreads) {
  write_point_cloud(path("in2.ply"), test::sample_sphere(1000, 0.5, Vector3d(-1, 0, 0), 7));
  std::size_t checked = 0;
  for (const StageSpec& s : registered_stages()) {
    if (s.shape == CommandShape::Read || s.shape == CommandShape::Write || s.measures()) continue;  // evaluations: tests/evaluate/evaluate_cli_test.cpp
    if (s.shape == CommandShape::Picture) continue;                     // render: tests/render/render_cli_test.cpp
    if (s.shape == CommandShape::Pair || s.name == "register-many") continue;  // tests/pipeline/register_cli_test.cpp
    const bool multi = s.takes_many();
    const std::string inputs = multi ? path("in.ply") + " " + path("in2.ply") : path("in.ply");
    const test::CliResult cli = test::run_cli(s.name + " " + inputs + " " + path("cli.ply") + " " + options_for(s.name, false) + " --threads 1", dir_);
    ASSERT_EQ(cli.exit_code, 0) << s.name << ": " << cli.err;
    std::string json = "[\"" + path("in.ply") + "\", " + (multi ? "\"" + path("in2.ply") + "\", " : std::string()) + "{\"type\": \"" + s.name +
                       "\"" + (options_for(s.name, true).empty() ? "" : ", " + options_for(s.name, true)) + "}, \"" + path("pipe.ply") + "\"]";
    const test::CliResult run = test::run_cli("run " + write_pipeline(s.name + ".json", json), dir_);
    ASSERT_EQ(run.exit_code, 0) << s.name << ": " << run.err;
    const std::string a = test::read_bytes(path("cli.ply")), b = test::read_bytes(path("pipe.ply"));
    EXPECT_FALSE(a.empty()) << s.name;
    EXPECT_TRUE(a == b) << s.name << ": the command (1 thread) and the pipeline (all threads) differ";
    std::filesystem::remove(path("cli.ply"));
    std::filesystem::remove(path("pipe.ply"));
    ++checked;
  }
  EXPECT_EQ(checked, registered_stages().size() - 7);  // all but read, write, quality, evaluate, render, register, register-many
}

TEST_F(RunCli, CommandLineFindsOutputProblemsBeforeTheWorkAndRefusesIgnoredOptions) {
  const std::string in = path("in.ply");
  test::CliResult r = test::run_cli("reconstruct " + in + " " + path("nowhere/m.ply"), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "directory " + path("nowhere") + " does not exist")) << r.err;
  r = test::run_cli("reconstruct " + in + " " + path("m.ply") + " --report " + path("nowhere/r.json"), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(path("m.ply")));
  test::write_bytes(dir_ / "exists.ply", "keep");
  r = test::run_cli("normals " + in + " " + path("exists.ply") + " --no-clobber", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "exists (--no-clobber)")) << r.err;
  EXPECT_EQ(test::read_bytes(dir_ / "exists.ply"), "keep");
  r = test::run_cli("normals " + in + " " + path("o.ply") + " --viewpoint 0,0,5", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--viewpoint: ignored unless orient is viewpoint")) << r.err;
  r = test::run_cli("normals " + in + " " + path("o.ply") + " --ascii --big-endian", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "ascii and big_endian: give only one")) << r.err;
  r = test::run_cli("normals " + in + " " + path("o.ply") + " --threads 100000", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--threads: 100000 exceeds the")) << r.err;
  r = test::run_cli("convert " + in + " " + path("o.las") + " --las-scale 0", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--las-scale: 0 is out of range (0, inf)")) << r.err;
  r = test::run_cli("nromals " + in + " " + path("o.ply"), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "unknown command \"nromals\"; did you mean \"normals\"?")) << r.err;
  r = test::run_cli("normals " + in + " " + path("o.ply") + " --kk 30", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "unknown option --kk; did you mean --k?")) << r.err;
  r = test::run_cli("normals " + in + " " + path("o.ply") + " --k abc", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--k: \"abc\" is not an integer")) << r.err;
  test::write_bytes(dir_ / "words.txt", "the quick brown fox\njumps over\n");
  r = test::run_cli("info " + path("words.txt"), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("o.ply")));
  r = test::run_cli("clean " + in + " " + path("o.ply") + " --method sor --std-ratio 3 --quiet", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
}

TEST_F(RunCli, StageHelpShowsItsOwnExamplesAndDefaults) {
  const test::CliResult normals = test::run_cli("normals --help", dir_);
  const test::CliResult clean = test::run_cli("clean --help", dir_);
  ASSERT_EQ(normals.exit_code, 0);
  EXPECT_TRUE(test::contains(normals.out, "--k N")) << normals.out;
  EXPECT_TRUE(test::contains(normals.out, "default 30")) << normals.out;
  EXPECT_TRUE(test::contains(clean.out, "--std-ratio X")) << clean.out;
  EXPECT_TRUE(test::contains(clean.out, "pointsurf clean data/b9_training.ply")) << clean.out;
  EXPECT_FALSE(test::contains(normals.out, "pointsurf clean data/b9_training.ply")) << normals.out;
}

}  // namespace
}  // namespace pointsurf

namespace pointsurf {
namespace {

TEST_F(RunCli, StagesOnAMeshKeepOrDropItsFacesAndSaySo) {
  const std::string in = path("in.ply");
  ASSERT_EQ(test::run_cli("reconstruct " + in + " " + path("mesh.ply") + " --quiet", dir_).exit_code, 0);
  const std::size_t faces = read_mesh(path("mesh.ply")).mesh.triangle_count();
  ASSERT_GT(faces, 0u);
  // normals keeps the points, and so the faces
  test::CliResult r = test::run_cli("normals " + path("mesh.ply") + " " + path("n.ply"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_mesh(path("n.ply")).mesh.triangle_count(), faces);
  // simplify changes them: the faces go, with a warning
  r = test::run_cli("simplify " + path("mesh.ply") + " " + path("s.ply") + " --ratio 0.5", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "warning: the input is a mesh: its " + std::to_string(faces) + " faces are dropped (simplify works on points)"))
      << r.err;
  EXPECT_EQ(read_mesh(path("s.ply")).mesh.triangle_count(), 0u);
  // the report says which cloud the mesh came from
  ASSERT_EQ(test::run_cli("reconstruct " + in + " " + path("m2.ply") + " --quiet --report " + path("r.json"), dir_).exit_code, 0);
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["stages"][1]["metrics"]["built_from"], "in1");
  EXPECT_EQ(report["stages"][2]["metrics"]["mesh_built_from"], "in1");
}

}  // namespace
}  // namespace pointsurf

namespace pointsurf {
namespace {

TEST_F(RunCli, ACommandRefusedAfterParsingStillWritesItsReport) {
  const test::CliResult r = test::run_cli("normals " + path("in.ply") + " " + path("o.ply") + " --k 1 --report " + path("r.json"), dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(test::contains(r.err, "--k: 1 is out of range [3, inf)")) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["command"], "normals");
  EXPECT_EQ(report["status"], "failed");
  EXPECT_EQ(report["error"]["exit_code"], 1);
  EXPECT_EQ(report["error"]["kind"], "usage");
  EXPECT_EQ(report["error"]["key"], "k");
  EXPECT_TRUE(report["stages"].empty());
  EXPECT_FALSE(std::filesystem::exists(path("o.ply")));
}

TEST_F(RunCli, ADirectoryWhereNoFileCanBeMadeIsRefusedBeforeAnyWork) {
  // /proc takes no new file, whatever access() answers for root.
  if (!std::filesystem::is_directory("/proc")) GTEST_SKIP() << "no /proc";
  const test::CliResult r = test::run_cli("normals " + path("in.ply") + " /proc/pointsurf_out.ply", dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(test::contains(r.err, "/proc/pointsurf_out.ply: cannot write in directory /proc")) << r.err;
  EXPECT_FALSE(test::contains(r.err, "[1/")) << "work was done before the refusal:\n" << r.err;
}

TEST_F(RunCli, AFailedRunStillWritesItsReport) {
  const std::string file = write_pipeline("f.json", "[\"" + path("in.ply") + "\", {\"type\": \"crop\", \"min\": [9, 9, 9]}, \"" + path("o.ply") + "\"]");
  const test::CliResult r = test::run_cli("run " + file + " --report " + path("r.json"), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(test::contains(r.err, "stage 2 (crop): no point is left")) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["status"], "failed");
  EXPECT_EQ(report["error"]["exit_code"], 2);
  ASSERT_EQ(report["stages"].size(), 2u);  // the read, and the stage that failed
  EXPECT_EQ(report["stages"][1]["type"], "crop");
  EXPECT_FALSE(std::filesystem::exists(path("o.ply")));
  // The error as data: kind and place apart from the words.
  const nlohmann::json& error = report["error"];
  EXPECT_EQ(error["kind"], "input");
  EXPECT_EQ(error["stage_index"], 2);
  EXPECT_EQ(error["stage"], "crop");
  EXPECT_TRUE(test::contains(error["text"].get<std::string>(), "no point is left")) << error;
  EXPECT_FALSE(test::contains(error["text"].get<std::string>(), "stage 2")) << error;
  EXPECT_FALSE(error.contains("key")) << error;

  // A usage error found before any work names its key; a missing input names its file.
  const std::string bad_key = write_pipeline("k.json", "[\"" + path("in.ply") + "\", {\"type\": \"normals\", \"k\": 2}, \"" + path("o.ply") + "\"]");
  EXPECT_EQ(test::run_cli("run " + bad_key + " --report " + path("r2.json"), dir_).exit_code, 1);
  const nlohmann::json usage = nlohmann::json::parse(test::read_bytes(path("r2.json")))["error"];
  EXPECT_EQ(usage["kind"], "usage");
  EXPECT_EQ(usage["key"], "k");
  EXPECT_EQ(usage["stage"], "normals");
  EXPECT_EQ(usage["exit_code"], 1);
  const std::string missing = write_pipeline("m.json", "[\"" + path("nowhere.ply") + "\", {\"type\": \"normals\"}, \"" + path("o.ply") + "\"]");
  EXPECT_EQ(test::run_cli("run " + missing + " --report " + path("r3.json"), dir_).exit_code, 2);
  const nlohmann::json input = nlohmann::json::parse(test::read_bytes(path("r3.json")))["error"];
  EXPECT_EQ(input["kind"], "input");
  EXPECT_EQ(input["file"], path("nowhere.ply"));
}

// The command line words a key as its option; the pipeline and the library keep the key.
TEST_F(RunCli, TheCommandLineNamesKeysAsOptions) {
  test::CliResult r = test::run_cli("simplify " + path("in.ply") + " " + path("o.ply") + " --method grid --region-angle-deg 20", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--region-angle-deg belongs to method regional, not to method grid")) << r.err;
  EXPECT_FALSE(test::contains(r.err, "stage ")) << r.err;  // a command is not a pipeline
  r = test::run_cli("transform " + path("in.ply") + " " + path("o.ply") + " --matrix 1,2,3", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--matrix: expected 16 numbers")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("o.ply")));
}

// The coordinate system of a LAS input: shown by info (text and JSON) and kept through
// read -> normals -> write LAZ.
TEST_F(RunCli, CoordinateSystemIsShownByInfoAndKeptThroughAStageChain) {
  PointCloud cloud = test::sample_sphere(500, 1.0, Vector3d(500'000.0, 5'000'000.0, 100.0));
  cloud.crs.wkt = "PROJCS[\"WGS 84 / UTM zone 33N\",GEOGCS[\"WGS 84\"],AUTHORITY[\"EPSG\",\"32633\"]]";
  write_point_cloud(path("geo.las"), cloud);
  test::CliResult r = test::run_cli("info " + path("geo.las"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.out, "crs          WGS 84 / UTM zone 33N (EPSG:32633)")) << r.out;
  r = test::run_cli("info " + path("geo.las") + " --json", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json info = nlohmann::json::parse(r.out);
  EXPECT_EQ(info["crs"]["epsg"], 32633);
  EXPECT_EQ(info["crs"]["wkt"], cloud.crs.wkt);

  const std::string file = write_pipeline("p.json", "[\"" + path("geo.las") + "\", {\"type\": \"normals\", \"k\": 12}, \"" + path("out.laz") + "\"]");
  r = test::run_cli("run " + file, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud back = read_point_cloud(path("out.laz")).cloud;
  EXPECT_TRUE(back.has_normals());
  EXPECT_EQ(back.crs.wkt, cloud.crs.wkt);

  // The boundary stage's GeoJSON outlines name the input's EPSG code when --crs is not given.
  PointCloud plate = test::sample_plane(4000, 1.0, 6);
  plate.crs.wkt = cloud.crs.wkt;
  write_point_cloud(path("plate.las"), plate);
  r = test::run_cli("boundary " + path("plate.las") + " " + path("rim.las") + " --outlines " + path("rim.geojson"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(test::read_bytes(path("rim.geojson")), "EPSG:32633"));
  EXPECT_EQ(read_point_cloud(path("rim.las")).cloud.crs.wkt, cloud.crs.wkt);

  // A WKT whose only authority is its unit's has no EPSG code: info says so and keeps the WKT;
  // the GeoJSON outlines name no CRS, and the stage warns.
  plate.crs.wkt = R"w(PROJCS["site grid (ftUS)",GEOGCS["NAD83"],UNIT["foot",0.3048,AUTHORITY["EPSG","9002"]]])w";
  write_point_cloud(path("feet.las"), plate);
  r = test::run_cli("info " + path("feet.las"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.out, "crs          site grid (ftUS) (no EPSG code)\n")) << r.out;
  r = test::run_cli("info " + path("feet.las") + " --json", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json feet = nlohmann::json::parse(r.out);
  EXPECT_FALSE(feet["crs"].contains("epsg")) << feet["crs"];
  EXPECT_EQ(feet["crs"]["name"], "site grid (ftUS) (no EPSG code)");
  EXPECT_EQ(feet["crs"]["wkt"], plate.crs.wkt);
  r = test::run_cli("boundary " + path("feet.las") + " " + path("feet_rim.las") + " --outlines " + path("feet.geojson"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "warning: the GeoJSON outlines name no CRS: the input's CRS is site grid (ftUS) (no EPSG code)")) << r.err;
  EXPECT_FALSE(nlohmann::json::parse(test::read_bytes(path("feet.geojson"))).contains("crs"));
  EXPECT_EQ(read_point_cloud(path("feet_rim.las")).cloud.crs.wkt, plate.crs.wkt);
}

}  // namespace
}  // namespace pointsurf
