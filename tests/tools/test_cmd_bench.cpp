// skelcd bench as a user runs it: the table, CSV (header, one line per method × accuracy, numbers
// that agree with --json), the PNG plot, and bad input refused in one line with nothing written.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"

namespace {

using skelcd::test::run_skelcd;

const std::string kRope = "gen:rope?triangles=1000&frames=60";

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(CmdBench, CsvJsonAndPlotOfAGeneratedRope) {
  const auto dir = skelcd::test::temp_dir("bench-cli");
  const auto csv = dir / "rope.csv";
  const auto png = dir / "rope.png";
  const auto r = run_skelcd(
      {"bench",
       kRope,
       "--frames",
       "44:46",
       "--methods",
       "bvh,kdop",
       "--accuracies",
       "exact,conservative,fast",
       "--csv",
       csv.string(),
       "--plot",
       png.string(),
       "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["reference"]["method"], "brute");
  EXPECT_EQ(j["reference"]["accuracy"], "exact");
  EXPECT_EQ(j["intervals"], 2);
  ASSERT_EQ(j["rows"].size(), 6u);
  EXPECT_EQ(j["rows"][0]["method"], "bvh");
  EXPECT_EQ(j["rows"][0]["accuracy"], "exact");
  EXPECT_EQ(j["rows"][5]["method"], "kdop");
  EXPECT_EQ(j["rows"][5]["accuracy"], "fast");
  for (const auto& row : j["rows"]) {
    if (row["accuracy"] != "fast") {
      EXPECT_EQ(row["false_negatives"], 0) << row.dump();
    }
    if (row["accuracy"] == "exact") {
      EXPECT_EQ(row["false_positives"], 0) << row.dump();
    }
    EXPECT_FALSE(row["reference"].get<bool>());  // brute is the reference, not in the table
  }

  const auto csv_lines = lines(read_text(csv));
  ASSERT_EQ(csv_lines.size(), 7u);
  EXPECT_EQ(
      csv_lines[0].rfind(
          "method,accuracy,ms_per_interval,bv_tests,candidate_pairs,contacts,"
          "false_negatives,false_positives,skin_ms,refit_ms,classify_ms,"
          "merge_ms,traverse_ms,elementary_ms,other_ms",
          0),
      0u)
      << csv_lines[0];
  // Row 2 (bvh conservative) carries the JSON's counts.
  std::ostringstream expected;
  expected << "bvh,conservative,";
  EXPECT_EQ(csv_lines[2].rfind(expected.str(), 0), 0u) << csv_lines[2];
  std::vector<std::string> fields;
  std::istringstream row(csv_lines[2]);
  for (std::string f; std::getline(row, f, ',');) fields.push_back(f);
  ASSERT_GE(fields.size(), 8u);
  EXPECT_EQ(fields[3], std::to_string(j["rows"][1]["bv_tests"].get<long long>()));
  EXPECT_EQ(fields[5], std::to_string(j["rows"][1]["contacts"].get<long long>()));
  EXPECT_EQ(fields[6], "0");

  // The plot is a PNG.
  const auto image = read_text(png);
  ASSERT_GT(image.size(), 1000u);
  EXPECT_EQ(image.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  // No temporary files left beside the outputs.
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++files;
  EXPECT_EQ(files, 2u);
}

TEST(CmdBench, TableOnARealCharacterMarksTheReference) {
  const auto model = skelcd::test::asset("characters/CesiumMan.glb").string();
  const auto r = run_skelcd(
      {"bench",
       model,
       "--frames",
       "0:2",
       "--methods",
       "brute,bvh",
       "--accuracies",
       "exact,conservative"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("reference brute + exact"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("* brute"), std::string::npos) << r.out;
  const auto out = lines(r.out);
  const auto rows = std::count_if(out.begin(), out.end(), [](const std::string& l) {
    return l.rfind("  bvh ", 0) == 0 || l.rfind("  brute ", 0) == 0 || l.rfind("* brute ", 0) == 0;
  });
  EXPECT_EQ(rows, 4);
}

TEST(CmdBench, EveryMethodOnABundledCharacterMissesNothingButDualCone) {
  // The acceptance on a bundled character: every method (the default list) at
  // conservative and fast against brute + exact; only dual-cone (FASTCD, by design) and fast (no
  // guarantee; it happens to miss nothing on these samples) may have false negatives, and
  // dual-cone does miss here.
  const auto model = skelcd::test::asset("characters/CesiumMan.glb").string();
  const auto r = run_skelcd(
      {"bench", model, "--frames", "0:3", "--accuracies", "conservative,fast", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["reference"]["method"], "brute");
  EXPECT_EQ(j["reference"]["accuracy"], "exact");
  std::set<std::string> methods;
  std::int64_t dual_cone_misses = 0;
  for (const auto& row : j["rows"]) {
    const std::string method = row["method"], accuracy = row["accuracy"];
    methods.insert(method);
    ASSERT_GT(row["contacts"].get<std::int64_t>(), 0) << method;
    if (method == "dual-cone") {
      dual_cone_misses += row["false_negatives"].get<std::int64_t>();
    } else if (accuracy != "fast") {
      EXPECT_EQ(row["false_negatives"], 0) << method << " " << accuracy;
    }
  }
  EXPECT_EQ(
      methods,
      (std::set<std::string>{
          "brute",
          "bvh",
          "kdop",
          "normal-cone",
          "dual-cone",
          "enhanced-dual-cone",
          "auto",
          "rvbc",
          "dynamic"}));
  EXPECT_GT(dual_cone_misses, 0);
}

TEST(CmdBench, AutoIsSegmentedOnlyWhereCheckSegmentsIt) {
  // `auto` gets a segmentation only for a closed group it sends to `dynamic`, decided as `check`
  // decides it: the bench's note is the check's `segmentation` value, word for word, for a garment
  // on its own skeleton (every part to the cones) and a character under 20,000 triangles (the
  // whole mesh to `bvh`); a denser character, whose closed body goes to `dynamic`, gets no note.
  // `auto` misses nothing against the reference either way, and `dynamic` beside it is still
  // segmented.
  const auto dense = skelcd::test::asset("characters/CesiumMan-dense.glb").string();
  const std::vector<std::pair<std::string, bool>> models = {
      {"gen:cloth", true},
      {skelcd::test::asset("characters/CesiumMan.glb").string(), true},
      {dense, false}};
  for (const auto& [model, without] : models) {
    const auto check = run_skelcd({"check", model, "--frames", "0:2", "--json"});
    ASSERT_EQ(check.exit_code, 0) << model << ": " << check.err;
    const std::string segmentation = nlohmann::json::parse(check.out)["segmentation"];
    EXPECT_EQ(segmentation.rfind("none (auto: ", 0) == 0, without) << model << ": " << segmentation;

    const auto r = run_skelcd(
        {"bench",
         model,
         "--frames",
         "0:2",
         "--methods",
         "auto,dynamic",
         "--accuracies",
         "conservative",
         "--reference",
         "bvh",
         "--json"});
    ASSERT_EQ(r.exit_code, 0) << model << ": " << r.err;
    const auto j = nlohmann::json::parse(r.out);
    const auto notes = j["notes"].get<std::vector<std::string>>();
    const std::string note = "auto: segmentation " + segmentation;
    EXPECT_EQ(std::count(notes.begin(), notes.end(), note), without ? 1 : 0)
        << model << ": " << r.out;
    if (!without) {
      for (const auto& n : notes) EXPECT_NE(n.rfind("auto: ", 0), 0u) << model << ": " << n;
    }
    ASSERT_EQ(j["rows"].size(), 2u) << r.out;
    for (const auto& row : j["rows"]) {
      EXPECT_EQ(row["false_negatives"], 0) << model << " " << row.dump();
      EXPECT_EQ(row["false_positives"], 0) << model << " " << row.dump();
    }
    // `dynamic` ran its radial view (a segmentation was made for it): its classify stage took time.
    const auto& dynamic = j["rows"][1];
    ASSERT_EQ(dynamic["method"], "dynamic");
    EXPECT_GT(dynamic["stages_ms"]["classify"].get<double>(), 0.0) << model;
  }
}

TEST(CmdBench, BadInputFailsWithOneLineAndWritesNothing) {
  const auto dir = skelcd::test::temp_dir("bench-bad");
  const auto csv = (dir / "out.csv").string();
  const auto png = (dir / "out.png").string();
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases{
      {{"bench", kRope, "--methods", "bvh,octree", "--csv", csv}, "octree"},
      {{"bench", kRope, "--accuracies", "exact,sloppy", "--csv", csv}, "sloppy"},
      {{"bench", (dir / "missing.glb").string(), "--csv", csv}, "missing.glb"},
      {{"bench", kRope, "--frames", "50:70", "--methods", "bvh", "--csv", csv, "--plot", png},
       "--frames"},
      {{"bench", kRope, "--reference", "kdop", "--csv", csv}, "--reference"},
      {{"bench", kRope, "--csv", (dir / "no-such-dir" / "out.csv").string()}, "no-such-dir"},
      {{"bench", kRope, "--plot", dir.string()}, dir.string()},
  };
  for (const auto& [args, needle] : cases) {
    const auto r = run_skelcd(args);
    SCOPED_TRACE(args[2] + " " + needle);
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_TRUE(std::filesystem::is_empty(dir)) << "left a file behind";
  }
}

TEST(CmdBench, RadialViewMethodsNeedARig) {
  const auto dir = skelcd::test::temp_dir("bench-rv");
  // A frame sequence has no skeleton: naming dynamic is refused, the default list leaves it out.
  const auto frames = skelcd::test::asset("cloth-funnel/frames").string();
  const auto r = run_skelcd({"bench", frames, "--methods", "dynamic"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("rigged"), std::string::npos) << r.err;
}

TEST(CmdBench, SceneRunsEachSelfCheckedObjectWithItsQueries) {
  const auto dir = skelcd::test::temp_dir("bench-scene");
  const auto scene = dir / "two.toml";
  {
    std::ofstream out(scene);
    out << "frames = \"44:46\"\n"
           "[objects.rope]\n"
           "model = \"gen:rope?triangles=1000&frames=60\"\n"
           "checks = [\"self-dcd\"]\n"
           "[objects.hand]\n"
           "model = \"gen:hand?triangles=1000&frames=60\"\n"
           "checks = [\"self-ccd\"]\n"
           "[objects.idle]\n"
           "model = \"gen:cloth?triangles=1000&frames=60\"\n";
  }
  const auto csv = dir / "s.csv";
  const auto png = dir / "s.png";
  const auto r = run_skelcd(
      {"bench",
       scene.string(),
       "--methods",
       "bvh",
       "--accuracies",
       "exact,conservative",
       "--csv",
       csv.string(),
       "--plot",
       png.string(),
       "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["objects"].size(), 2u);  // idle has no self check
  EXPECT_EQ(j["objects"][0]["object"], "rope");
  EXPECT_EQ(j["objects"][0]["query"], "dcd");  // from the object's checks
  EXPECT_EQ(j["objects"][0]["first_sample"], 44);
  EXPECT_EQ(j["objects"][0]["last_sample"], 46);
  EXPECT_EQ(j["objects"][1]["object"], "hand");
  EXPECT_EQ(j["objects"][1]["query"], "ccd");
  EXPECT_EQ(j["objects"][1]["intervals"], 2);
  for (const auto& o : j["objects"]) {
    for (const auto& row : o["rows"]) EXPECT_EQ(row["false_negatives"], 0) << row.dump();
  }
  // One CSV with an object column; one plot per object.
  const auto csv_lines = lines(read_text(csv));
  ASSERT_EQ(csv_lines.size(), 5u);
  EXPECT_NE(csv_lines[0].find(",object"), std::string::npos);
  EXPECT_NE(csv_lines[1].find(",rope"), std::string::npos);
  EXPECT_NE(csv_lines[4].find(",hand"), std::string::npos);
  for (const char* name : {"s_rope.png", "s_hand.png"}) {
    EXPECT_EQ(read_text(dir / name).substr(0, 4), std::string("\x89PNG", 4)) << name;
  }
  EXPECT_FALSE(std::filesystem::exists(png));

  // A sheet (built only by the scene runner) is benchmarked as the scene's checks see it: the
  // reference's findings equal what `check SCENE` finds for that object over the same samples.
  const auto with_sheet = dir / "sheet.toml";
  {
    std::ofstream out(with_sheet);
    out << "frames = \"0:3\"\n[objects.body]\nmodel = \""
        << skelcd::test::asset("characters/CesiumMan.glb").string()
        << "\"\n[objects.cape]\nsheet = { corner = [-0.12, 0.95, -0.25], u = [0.24, 0, 0], "
           "v = [0, -0.45, 0], cells = [12, 20] }\nattach_to = \"body\"\nchecks = [\"self-ccd\"]\n"
           "[[pairs]]\nobjects = [\"body\", \"cape\"]\nchecks = [\"dcd\"]\n";
  }
  const auto sheet = run_skelcd(
      {"bench",
       with_sheet.string(),
       "--methods",
       "bvh,enhanced-dual-cone",
       "--accuracies",
       "conservative",
       "--json"});
  ASSERT_EQ(sheet.exit_code, 0) << sheet.err;
  const auto js = nlohmann::json::parse(sheet.out);
  ASSERT_EQ(js["objects"].size(), 1u);
  EXPECT_EQ(js["objects"][0]["object"], "cape");
  EXPECT_EQ(js["objects"][0]["model"], "sheet on body");
  ASSERT_EQ(js["skipped"].size(), 1u);
  EXPECT_EQ(js["skipped"][0].get<std::string>().rfind("pair body cape", 0), 0u);
  const auto check = run_skelcd({"check", with_sheet.string(), "--json"});
  ASSERT_EQ(check.exit_code, 0) << check.err;
  const auto jc = nlohmann::json::parse(check.out);
  std::int64_t cape_contacts = -1;
  for (const auto& c : jc["checks"]) {
    if (c["name"] == "self cape")
      cape_contacts = c["ccd_vf"].get<std::int64_t>() + c["ccd_ee"].get<std::int64_t>();
  }
  ASSERT_GT(cape_contacts, 0) << "the cape must fold onto itself for this to mean anything";
  EXPECT_EQ(js["objects"][0]["reference"]["findings"], cape_contacts);
  for (const auto& row : js["objects"][0]["rows"])
    EXPECT_EQ(row["false_negatives"], 0) << row.dump();

  // A scene with no self check at all: nothing bench can run, one line, nothing written.
  const auto pairs_only = dir / "pairs.toml";
  {
    std::ofstream out(pairs_only);
    out << "[objects.a]\nmodel = \"gen:rope?triangles=200\"\n[objects.b]\nmodel = "
           "\"gen:rope?triangles=200\"\n"
           "offset = [5, 0, 0]\n[[pairs]]\nobjects = [\"a\", \"b\"]\nchecks = [\"dcd\"]\n";
  }
  const auto bad = run_skelcd({"bench", pairs_only.string(), "--csv", (dir / "x.csv").string()});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  EXPECT_NE(bad.err.find("no object has a self check"), std::string::npos) << bad.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.csv"));
}

}  // namespace
