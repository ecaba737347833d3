// skelcd info, as a user runs it: JSON and human output on real models, and bad input.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"

namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;
using skelcd::test::run_skelcd;

nlohmann::json info_json(const std::string& model) {
  const auto r = run_skelcd({"info", model, "--json"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  return nlohmann::json::parse(r.out);  // throws (fails the test) unless stdout is one JSON document
}

TEST(CmdInfo, BcnEpilepticAsAssimpInfoReportsIt) {
  const auto j = info_json(assimp_model("X/BCN_Epileptic.X").string());
  EXPECT_EQ(j["triangles"], 5126);
  EXPECT_EQ(j["bones"], 54);
  ASSERT_EQ(j["clips"].size(), 1u);
  EXPECT_EQ(j["clips"][0]["name"], "Epileptisch");
  EXPECT_NEAR(j["clips"][0]["duration_s"].get<double>(), 3.3, 1e-12);
  EXPECT_NEAR(j["clips"][0]["keys_per_s"].get<double>(), 30.0, 1e-9);
  ASSERT_EQ(j["parts"].size(), 3u);
  EXPECT_EQ(j["parts"][0]["name"], "Torso");
  EXPECT_EQ(j["parts"][0]["triangles"], 1966);
  for (const auto& p : j["parts"]) EXPECT_TRUE(p.contains("closed"));
  EXPECT_TRUE(j["problems"].is_array());
  for (const char* key : {"vertices", "welded_vertices", "edges", "boundary_loops", "non_manifold_edges", "degenerate_triangles"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
}

// Triangle count of a binary STL, read from its header (independent of assimp).
std::uint32_t stl_triangles(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(80);
  std::uint32_t n = 0;
  in.read(reinterpret_cast<char*>(&n), sizeof n);
  EXPECT_TRUE(in.good()) << path;
  EXPECT_EQ(std::filesystem::file_size(path), 84u + 50u * n) << path << " is not a binary STL";
  return n;
}

TEST(CmdInfo, UrdfRobotReportsItsCollisionGeometryAndTrajectory) {
  // The Panda: one part per link with geometry, each link's collision STL as written (the fingers
  // are four boxes each, 12 triangles a box), the trajectory as its clip, and the links that have
  // no geometry named as a problem.
  const auto root = asset("robots/example-robot-data/robots/panda_description");
  const auto csv = asset("trajectories/panda_reach.csv");
  const auto r = run_skelcd(
      {"info",
       (root / "urdf/panda.urdf").string(),
       "--trajectory",
       csv.string(),
       "--srdf",
       (root / "srdf/panda.srdf").string(),
       "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["kind"], "robot");
  const std::vector<std::pair<std::string, std::string>> links = {
      {"panda_link0", "link0.stl"},
      {"panda_link1", "link1.stl"},
      {"panda_link2", "link2.stl"},
      {"panda_link3", "link3.stl"},
      {"panda_link4", "link4.stl"},
      {"panda_link5", "link5.stl"},
      {"panda_link6", "link6.stl"},
      {"panda_link7", "link7.stl"},
      {"panda_hand", "hand.stl"}};
  ASSERT_EQ(j["parts"].size(), links.size() + 2);
  std::int64_t total = 0;
  for (std::size_t i = 0; i < links.size(); ++i) {
    const auto& part = j["parts"][i];
    EXPECT_EQ(part["name"], links[i].first);
    const auto expected = stl_triangles(root / "meshes/collision" / links[i].second);
    EXPECT_EQ(part["triangles"], expected) << links[i].first;
    EXPECT_EQ(part["closed"], true) << links[i].first;
    total += expected;
  }
  for (std::size_t i = links.size(); i < links.size() + 2; ++i) {
    EXPECT_EQ(j["parts"][i]["triangles"], 4 * 12) << j["parts"][i]["name"];
    total += 4 * 12;
  }
  EXPECT_EQ(j["parts"][links.size()]["name"], "panda_leftfinger");
  EXPECT_EQ(j["triangles"], total);
  EXPECT_EQ(j["bones"], links.size() + 2);  // one bone per link with geometry
  // The clip is the trajectory: its last row's time and its row rate.
  std::ifstream in(csv);
  std::string line, last;
  int rows = -1;  // the header
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    ++rows;
  }
  const double duration = std::stod(last.substr(0, last.find(',')));
  ASSERT_EQ(j["clips"].size(), 1u);
  EXPECT_EQ(j["clips"][0]["name"], "panda_reach");
  EXPECT_DOUBLE_EQ(j["clips"][0]["duration_s"].get<double>(), duration);
  EXPECT_NEAR(j["clips"][0]["keys_per_s"].get<double>(), (rows - 1) / duration, 1e-9);
  EXPECT_NEAR(j["clips"][0]["rate_hz"].get<double>(), (rows - 1) / duration, 1e-9);  // every row
  EXPECT_EQ(j["clips"][0]["rate_source"], "trajectory_rows");
  const std::string problems = j["problems"].dump();
  EXPECT_NE(problems.find("panda_link8"), std::string::npos) << problems;
  EXPECT_NE(problems.find("panda_hand_tcp"), std::string::npos) << problems;
}

// The 3ds Max <frame_rate> a Collada file carries, read from its text (0 when it has none).
double collada_frame_rate(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string tag = "<technique profile=\"MAX3D\"><frame_rate>";
  const auto at = text.find(tag);
  return at == std::string::npos ? 0.0 : std::stod(text.substr(at + tag.size()));
}

// The rate `check --json` reports for the first samples of `model` (and `extra` arguments).
double check_rate(const std::string& model, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> args = {
      "check",
      model,
      "--frames",
      "0:1",
      "--json",
      "--threads",
      "1",
      "-o",
      (skelcd::test::temp_dir("cmd_info_rate") / "log.h5").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const auto r = run_skelcd(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return nlohmann::json::parse(r.out)["fps"].get<double>();
}

std::string rate_text(double hz) {
  char text[64];
  std::snprintf(text, sizeof text, "%.6g", hz);
  return text;
}

TEST(CmdInfo, EachClipSaysTheRateACheckSamplesItAtAndWhy) {
  // A Collada file from 3ds Max declares its frame rate; its keys (about 3 s apart) do not set it.
  const auto dae = assimp_model("Collada/anims_with_full_rotations_between_keys.DAE").string();
  const double declared = collada_frame_rate(dae);
  ASSERT_GT(declared, 0.0);
  const auto j = info_json(dae);
  ASSERT_FALSE(j["clips"].empty());
  EXPECT_EQ(j["clips"][0]["rate_hz"].get<double>(), declared);
  EXPECT_EQ(j["clips"][0]["rate_source"], "file");
  EXPECT_LT(j["clips"][0]["keys_per_s"].get<double>(), 0.5 * declared);
  EXPECT_EQ(check_rate(dae), declared);
  const auto text = run_skelcd({"info", dae});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(
      text.out.find("sampled at " + rate_text(declared) + " Hz (the file's frame rate)"),
      std::string::npos)
      << text.out;

  // A glTF declares none, and two keys 1.25 s apart are no frame grid: 30 Hz by default, and
  // --fps still decides.
  const auto figure = asset("characters/RiggedFigure.glb").string();
  const auto g = info_json(figure);
  ASSERT_EQ(g["clips"].size(), 1u);
  EXPECT_EQ(g["clips"][0]["rate_hz"].get<double>(), 30.0);
  EXPECT_EQ(g["clips"][0]["rate_source"], "default");
  EXPECT_EQ(check_rate(figure), 30.0);
  EXPECT_EQ(check_rate(figure, {"--fps", "12"}), 12.0);
  const auto figure_text = run_skelcd({"info", figure});
  EXPECT_NE(
      figure_text.out.find("sampled at 30 Hz (default: no frame rate in the file)"),
      std::string::npos)
      << figure_text.out;
}

TEST(CmdInfo, ClosedCharacterAndOpenParts) {
  const auto cesium = info_json(asset("characters/CesiumMan.glb").string());
  EXPECT_EQ(cesium["triangles"], 4672);
  EXPECT_EQ(cesium["bones"], 19);
  ASSERT_EQ(cesium["parts"].size(), 1u);
  EXPECT_TRUE(cesium["parts"][0]["closed"].get<bool>());
  EXPECT_EQ(cesium["boundary_loops"], 0);
  const auto robot = info_json(asset("characters/RobotExpressive.glb").string());
  EXPECT_EQ(robot["clips"].size(), 14u);
  EXPECT_EQ(robot["degenerate_triangles"], 3);
  bool open = false;
  for (const auto& p : robot["parts"]) open |= !p["closed"].get<bool>();
  EXPECT_TRUE(open);
  bool reported = false;
  for (const auto& p : robot["problems"]) reported |= p.get<std::string>().find("degenerate triangles") != std::string::npos;
  EXPECT_TRUE(reported);
}

TEST(CmdInfo, AHandWrittenCubeHasEighteenEdgesAndIsClosed) {
  const auto dir = skelcd::test::temp_dir("cmd_info_cube");
  const auto file = dir / "cube.obj";
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\nv 0 1 1\nv 1 1 1\n"
                         "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  const auto j = info_json(file.string());
  EXPECT_EQ(j["triangles"], 12);
  EXPECT_EQ(j["edges"], 18);
  EXPECT_EQ(j["welded_vertices"], 8);
  EXPECT_EQ(j["bones"], 0);
  EXPECT_EQ(j["clips"].size(), 0u);
  ASSERT_EQ(j["parts"].size(), 1u);
  EXPECT_TRUE(j["parts"][0]["closed"].get<bool>());
}

TEST(CmdInfo, HumanSummary) {
  const auto r = run_skelcd({"info", assimp_model("X/BCN_Epileptic.X").string()});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("5126 triangles"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("54 bones"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("Epileptisch  3.300 s"), std::string::npos) << r.out;
}

TEST(CmdInfo, Help) {
  const auto r = run_skelcd({"info", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("--json"), std::string::npos);
}

// Bad input: exit 1, exactly one line on stderr naming the file, nothing on stdout.
void expect_refused(const std::string& model, const std::string& fault) {
  const auto r = run_skelcd({"info", model, "--json"});
  EXPECT_EQ(r.exit_code, 1) << model;
  EXPECT_TRUE(r.out.empty()) << r.out;
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
  EXPECT_NE(r.err.find(model), std::string::npos) << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
}

TEST(CmdInfo, BadInputIsOneLineAndNonZeroExit) {
  const auto dir = skelcd::test::temp_dir("cmd_info_bad");
  expect_refused((dir / "missing.glb").string(), "no such file");
  expect_refused(assimp_model("glTF2/IndexOutOfRange/IndexOutOfRange.gltf").string(), "out-of-range");
  expect_refused(assimp_model("glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb").string(), "non-finite");
  expect_refused(assimp_model("glTF2/RecursiveNodes/RecursiveNodes.gltf").string(), "recursive");
  expect_refused(assimp_model("glTF2/MissingBin/BoxTextured.gltf").string(), "BoxTextured0.bin");
  expect_refused(assimp_model("glTF2/SchemaFailures/sceneWrongType.gltf").string(), "scene");
  const auto nan = dir / "nan.obj";
  std::ofstream(nan) << "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n";
  expect_refused(nan.string(), "non-finite");
  const auto empty = dir / "empty.glb";
  std::ofstream{empty};
  expect_refused(empty.string(), "empty file");
}

}  // namespace
