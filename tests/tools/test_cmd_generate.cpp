// skelcd generate, as a user runs it: the list, PLY frames that read back bit-exactly as what the
// rig's Motion gives, the Panda's CSV (the bundled file is its output), and refused input.

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "skinning/frame_sequence.hpp"
#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"

namespace {

namespace fs = std::filesystem;
using skelcd::test::run_skelcd;

std::string read_all(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(CmdGenerate, ListsEveryGenerator) {
  const auto r = run_skelcd({"generate", "--list", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  std::vector<std::string> names;
  for (const auto& g : j["generators"]) {
    names.push_back(g["name"].get<std::string>());
    EXPECT_TRUE(g.contains("known_answer"));
    EXPECT_TRUE(g["closed"].is_boolean());
  }
  EXPECT_EQ(names, (std::vector<std::string>{"rope", "octopus", "hand", "pipe", "cloth", "panda", "panda-free"}));
  const auto text = run_skelcd({"generate", "--list"});
  EXPECT_EQ(text.exit_code, 0);
  EXPECT_NE(text.out.find("octopus"), std::string::npos);
  const auto help = run_skelcd({"generate", "--help"});
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--triangles"), std::string::npos);
}

TEST(CmdGenerate, PlyFramesReadBackExactly) {
  const fs::path dir = skelcd::test::temp_dir("cmd_generate_frames");
  const fs::path out = dir / "rope";
  const auto r = run_skelcd({"generate", "rope", "--triangles", "1500", "--frames", "12", "-o", out.string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["spec"], "gen:rope?triangles=1500&frames=12");
  EXPECT_EQ(j["frames"], 12);
  EXPECT_EQ(j["format"], "PLY frames");
  EXPECT_GE(j["known_answer"]["last_free_frame"].get<int>(), 0);

  // The same rig in process, and its Motion, against the frames as the loader reads them.
  const auto g = skelcd::skinning::generate(skelcd::skinning::parse_generator_spec("gen:rope?triangles=1500&frames=12"));
  EXPECT_EQ(j["triangles"], g.rig.mesh.num_triangles());
  EXPECT_EQ(j["known_answer"]["first_intersecting_frame"], g.answer.first_intersecting_frame);
  auto rig = std::make_shared<const skelcd::skinning::Rig>(g.rig);
  skelcd::skinning::RigMotionOptions options;
  options.clip = 0;
  const skelcd::skinning::RigMotion motion(rig, options);
  // In the files' order, to compare them with the rig index for index (a check holds them in a
  // spatial order).
  skelcd::skinning::LoadOptions file_order;
  file_order.mesh_order = skelcd::skinning::MeshOrder::file;
  const auto model = skelcd::skinning::load_model(out, file_order);
  EXPECT_EQ(model.kind, skelcd::skinning::ModelKind::frame_sequence);
  const auto frames = model.motion({});
  ASSERT_EQ(frames->num_samples(), 12);
  EXPECT_EQ(frames->mesh().triangles, g.rig.mesh.triangles);
  skelcd::skinning::Positions a;
  skelcd::skinning::Positions b;
  for (int i = 0; i < 12; ++i) {
    motion.positions(i, a);
    frames->positions(i, b);
    EXPECT_EQ(a, b) << "frame " << i;  // bit for bit
    EXPECT_DOUBLE_EQ(frames->sample_time(i), motion.sample_time(i));
  }
  // info reads the folder as any other model.
  const auto info = run_skelcd({"info", out.string(), "--json"});
  ASSERT_EQ(info.exit_code, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["triangles"], g.rig.mesh.num_triangles());

  // An existing non-empty folder is not overwritten.
  const std::string first = read_all(out / "frame_00.ply");
  const auto again = run_skelcd({"generate", "cloth", "--triangles", "500", "--frames", "3", "-o", out.string()});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.err.find("exists and is not an empty folder"), std::string::npos) << again.err;
  EXPECT_EQ(read_all(out / "frame_00.ply"), first);
  EXPECT_FALSE(fs::exists(out / "frame_2.ply"));
}

TEST(CmdGenerate, PandaTrajectoryCsvIsTheBundledOne) {
  const fs::path dir = skelcd::test::temp_dir("cmd_generate_panda");
  for (const std::string name : {"panda", "panda-free"}) {
    const fs::path csv = dir / (name + ".csv");
    const auto r = run_skelcd({"generate", name, "--frames", "61", "-o", csv.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("joint trajectory CSV"), std::string::npos);
    const auto bundled = skelcd::test::asset(name == "panda" ? "trajectories/panda_reach.csv" : "trajectories/panda_free.csv");
    EXPECT_EQ(read_all(csv), read_all(bundled)) << csv;
  }
  const auto r = run_skelcd({"generate", "panda", "-o", (dir / "reach.csv").string(), "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["known_answer"]["last_free_frame"], 37);
  EXPECT_EQ(j["known_answer"]["first_intersecting_frame"], 38);
}

TEST(CmdGenerate, BadInputIsOneLineAndWritesNothing) {
  const fs::path dir = skelcd::test::temp_dir("cmd_generate_bad");
  const auto expect_error = [&](const std::vector<std::string>& args, const std::string& message) {
    const auto r = run_skelcd(args);
    EXPECT_EQ(r.exit_code, 1) << message;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  };
  expect_error({"generate", "squid", "-o", (dir / "x").string()}, "unknown generator 'squid'");
  expect_error({"generate", "rope", "--triangles", "10", "-o", (dir / "x").string()}, "triangles = 10 is outside");
  expect_error({"generate", "rope", "--frames", "1", "-o", (dir / "x").string()}, "frames = 1 is outside");
  expect_error({"generate", "rope", "-o", (dir / "x.csv").string()}, "is written as a folder of PLY frames");
  expect_error({"generate", "rope", "-o", (dir / "x.glb").string()}, "write a folder of PLY frames");
  expect_error({"generate", "panda", "--triangles", "1000", "-o", (dir / "p.csv").string()}, "fixed size");
  expect_error({"generate", "rope"}, "give -o OUT");
  expect_error({"generate", "rope", "--frames", "3", "-o", (dir / "missing" / "x").string()}, "no such folder");
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
