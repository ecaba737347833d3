// skelcd export, as a user runs it: posed frames read back through assimp (our importer), the
// formats, standard output, and refusals that leave nothing behind.

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "skinning/assimp_import.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"

namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;
using skelcd::test::run_skelcd;

const std::string kBcn = assimp_model("X/BCN_Epileptic.X").string();

skelcd::skinning::Rig read_back(const std::filesystem::path& file) {
  // Read as written: no merging of vertices.
  return skelcd::skinning::import_rig(file, {.join_identical_vertices = false, .convert_to_metres = false}).rig;
}

TEST(CmdExport, FrameTenReadsBackWithAllFacesAndDiffersFromFrameZero) {
  const auto dir = skelcd::test::temp_dir("cmd_export_frames");
  const auto f0 = dir / "frame0.obj";
  const auto f10 = dir / "frame10.obj";
  auto r = run_skelcd({"export", kBcn, "--frame", "0", "-o", f0.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_skelcd({"export", kBcn, "--frame", "10", "-o", f10.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("frame 10"), std::string::npos) << r.out;
  const auto a = read_back(f0);
  const auto b = read_back(f10);
  EXPECT_EQ(a.mesh.num_triangles(), 5126);
  EXPECT_EQ(b.mesh.num_triangles(), 5126);
  ASSERT_EQ(a.mesh.num_vertices(), b.mesh.num_vertices());
  EXPECT_GT((a.mesh.rest_positions - b.mesh.rest_positions).cwiseAbs().maxCoeff(), 1e-3);
  // Frame 0 is the clip's first pose: the bind positions up to float rounding for this file.
  const auto rest = skelcd::skinning::import_rig(kBcn).rig;
  EXPECT_EQ(a.mesh.part_names, rest.mesh.part_names);
}

TEST(CmdExport, TimeAndFrameAgreeAtASampleTime) {
  // BCN's clip has 30 keys/s: frame 15 is t = 0.5 s.
  const auto dir = skelcd::test::temp_dir("cmd_export_time");
  const auto by_frame = dir / "frame.ply";
  const auto by_time = dir / "time.ply";
  ASSERT_EQ(run_skelcd({"export", kBcn, "--frame", "15", "-o", by_frame.string()}).exit_code, 0);
  ASSERT_EQ(run_skelcd({"export", kBcn, "--time", "0.5", "-o", by_time.string()}).exit_code, 0);
  const auto a = read_back(by_frame);
  const auto b = read_back(by_time);
  EXPECT_EQ(a.mesh.num_triangles(), 5126);
  EXPECT_TRUE(skelcd::test::expect_matrix_near(a.mesh.rest_positions, b.mesh.rest_positions, 0.0));
}

TEST(CmdExport, GlbKeepsPartsAndPlyWorksToo) {
  const auto dir = skelcd::test::temp_dir("cmd_export_glb");
  const auto glb = dir / "posed.glb";
  ASSERT_EQ(run_skelcd({"export", asset("characters/RobotExpressive.glb").string(), "--clip", "Wave", "--frame", "5", "-o",
                        glb.string()})
                .exit_code,
            0);
  const auto robot = read_back(glb);
  EXPECT_EQ(robot.mesh.num_triangles(), 3237);
  EXPECT_EQ(robot.mesh.num_parts(), 19);
}

TEST(CmdExport, StandardOutput) {
  const auto r = run_skelcd({"export", asset("characters/Fox.glb").string(), "--clip", "Walk", "-o", "-", "--format", "ply"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("ply\n", 0), 0u) << r.out.substr(0, 40);
  EXPECT_NE(r.err.find("standard output"), std::string::npos) << r.err;  // the summary goes to stderr
  const auto obj = run_skelcd({"export", asset("characters/Fox.glb").string(), "-o", "/dev/stdout"});
  ASSERT_EQ(obj.exit_code, 0) << obj.err;
  EXPECT_NE(obj.out.find("\nf "), std::string::npos);  // OBJ by default on standard output
}

TEST(CmdExport, Help) {
  const auto r = run_skelcd({"export", "--help"});
  EXPECT_EQ(r.exit_code, 0);
  for (const char* option : {"--clip", "--frame", "--time", "--rate", "-o"}) {
    EXPECT_NE(r.out.find(option), std::string::npos) << option;
  }
}

// Refusals: exit 1, one line naming the model, and no output file (nor a temporary) left.
void expect_refused(const std::vector<std::string>& args, const std::filesystem::path& dir, const std::string& fault) {
  const auto r = run_skelcd(args);
  EXPECT_EQ(r.exit_code, 1);
  ASSERT_FALSE(r.err.empty());
  EXPECT_EQ(r.err.find('\n'), r.err.size() - 1) << "not one line: " << r.err;
  EXPECT_NE(r.err.find(fault), std::string::npos) << r.err;
  EXPECT_TRUE(std::filesystem::is_empty(dir)) << "something was written to " << dir;
}

TEST(CmdExport, BadRequestsWriteNothing) {
  const auto dir = skelcd::test::temp_dir("cmd_export_bad");
  const auto out = (dir / "out.obj").string();
  expect_refused({"export", kBcn, "--frame", "100", "-o", out}, dir, kBcn + ": frame 100 out of range");
  expect_refused({"export", kBcn, "--frame", "-1", "-o", out}, dir, "out of range");
  expect_refused({"export", kBcn, "--time", "9", "-o", out}, dir, "outside");
  expect_refused({"export", kBcn, "--clip", "Dance", "-o", out}, dir, "no clip named 'Dance'");
  expect_refused({"export", kBcn, "-o", (dir / "out.xyz").string()}, dir, "unknown output format");
  expect_refused({"export", kBcn, "-o", (dir / "no_such_folder" / "out.obj").string()}, dir, "does not exist");
  expect_refused({"export", (dir / "missing.glb").string(), "-o", out}, dir, "no such file");
  expect_refused({"export", assimp_model("glTF2/IndexOutOfRange/IndexOutOfRange.gltf").string(), "-o", out}, dir, "out-of-range");
  // --frame and --time together are a usage error.
  const auto both = run_skelcd({"export", kBcn, "--frame", "1", "--time", "0.1", "-o", out});
  EXPECT_NE(both.exit_code, 0);
  EXPECT_TRUE(std::filesystem::is_empty(dir));
}

}  // namespace
