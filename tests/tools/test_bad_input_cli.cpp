// Bad input and hostile conditions at the command line, as a user meets them: one line on stderr
// naming the file and the fault, a non-zero exit, nothing half-written (issue "Real files and bad
// files", items 4, 6, 7, 11, 12, 13).

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "skinning/assimp_import.hpp"
#include "tests/support/test_support.hpp"
#include "tests/tools/cli_runner.hpp"
#include "tools/io/log/log_reader.hpp"

namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;
using skelcd::test::run_skelcd;
using skelcd::test::temp_dir;

std::size_t count_lines(const std::string& text) {
  std::size_t n = 0;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) ++n;
  return n;
}

std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// --- 6. a rate of 0 is refused like a negative one, by every command that takes one ------------

TEST(BadInputCli, ZeroAndNegativeRatesAreRefusedAlikeByEveryCommand) {
  const auto model = asset("characters/RiggedFigure.glb").string();
  const auto out = (temp_dir("rates") / "out.obj").string();
  const std::vector<std::vector<std::string>> commands = {
      {"check", model, "--fps"},
      {"bench", model, "--fps"},
      {"preprocess", model, "--clip", "clip_0", "--fps"},
      {"export", model, "-o", out, "--rate"}};
  for (const auto& base : commands) {
    for (const std::string value : {"0", "-5", "nan"}) {
      auto args = base;
      args.push_back(value);
      const auto r = run_skelcd(args);
      const std::string flag = base.back();
      EXPECT_EQ(r.exit_code, 1) << base.front() << " " << flag << " " << value << ": " << r.err;
      EXPECT_EQ(count_lines(r.err), 1u) << r.err;
      EXPECT_NE(
          r.err.find(flag + " " + value + ": expected a rate > 0 (samples/s)"), std::string::npos)
          << r.err;
    }
  }
}

// --- 7. an unknown method lists every method -----------------------------------------------

TEST(BadInputCli, AnUnknownMethodListsEveryMethodRadialViewIncluded) {
  for (const std::string query : {"both", "dcd"}) {
    const auto r = run_skelcd(
        {"check",
         asset("characters/RiggedFigure.glb").string(),
         "--method",
         "octree",
         "--query",
         query});
    EXPECT_EQ(r.exit_code, 1);
    EXPECT_EQ(count_lines(r.err), 1u) << r.err;
    for (const std::string m :
         {"brute",
          "bvh",
          "kdop",
          "normal-cone",
          "dual-cone",
          "enhanced-dual-cone",
          "rvbc",
          "dynamic",
          "auto"}) {
      EXPECT_NE(r.err.find(m), std::string::npos) << m << " missing from: " << r.err;
    }
  }
}

// --- 12. a batch's failures name the file once; assimp prints nothing of its own ---------------

TEST(BadInputCli, BatchFailuresNameTheFileOnce) {
  const auto dir = temp_dir("batch-names");
  const auto missing = (dir / "missing.glb").string();
  const auto r = run_skelcd(
      {"check",
       asset("characters/RiggedFigure.glb").string(),
       missing,
       "-o",
       (dir / "logs").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_EQ(occurrences(r.err, "missing.glb"), 1u) << r.err;
  EXPECT_NE(r.err.find("first " + missing + ": no such file"), std::string::npos) << r.err;
  EXPECT_EQ(occurrences(r.out, "missing.glb"), 1u) << r.out;
}

TEST(BadInputCli, AssimpsOwnPrintingNeverReachesTheTerminal) {
  const auto file = assimp_model("OpenGEX/empty_camera.ogex").string();
  const auto r = run_skelcd({"info", file});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.out, "");
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_EQ(r.err.rfind("skelcd: " + file + ": ", 0), 0u) << r.err;
}

// --- 3. a file that lies about its size, at the command line ------------------------------------

TEST(BadInputCli, AFileDeclaringFifteenGigabytesIsOneLine) {
  const auto file = assimp_model("invalid/OutOfMemory.off").string();
  const auto r = run_skelcd({"info", file});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(count_lines(r.err), 1u) << r.err;
  EXPECT_NE(r.err.find(file + ": declares 353535235358 vertices"), std::string::npos) << r.err;
  // And a real character under a memory limit it cannot meet.
  const auto fox = asset("characters/Fox.glb").string();
  const auto small = run_skelcd({"info", fox, "--import-memory", "64"});
  EXPECT_EQ(small.exit_code, 0) << small.err;  // 64 MiB is plenty for 576 triangles
  const auto bad = run_skelcd({"info", fox, "--import-memory", "0"});
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_EQ(bad.err, "skelcd: --import-memory 0: expected MiB between 64 and 1048576\n");
}

// --- 2. one broken clip: info lists it, check takes any sound one ------------------------------

TEST(BadInputCli, TheNinjaLoadsAndEverySoundClipCanBeChecked) {
  const auto ninja = asset("characters/ninja/ninja.mesh").string();
  const auto info = run_skelcd({"info", ninja});
  EXPECT_EQ(info.exit_code, 0) << info.err;
  EXPECT_NE(info.out.find("clips:    18"), std::string::npos) << info.out;
  EXPECT_NE(info.out.find("clip 'HighJump' refused"), std::string::npos) << info.out;
  const auto walk =
      run_skelcd({"check", ninja, "--clip", "Walk", "--frames", "0:2", "--query", "dcd"});
  EXPECT_EQ(walk.exit_code, 0) << walk.err;
  const auto broken = run_skelcd({"check", ninja, "--clip", "HighJump"});
  EXPECT_EQ(broken.exit_code, 1);
  EXPECT_EQ(count_lines(broken.err), 1u) << broken.err;
  EXPECT_NE(
      broken.err.find("clip 'HighJump' was refused: node 'Joint1', translation key 1"),
      std::string::npos)
      << broken.err;
}

// --- 11. glb export: one mesh per part, named as the part -----------------------------------

TEST(BadInputCli, GlbExportHasOneMeshPerPartNamedAsThePart) {
  const auto robot = asset("characters/RobotExpressive.glb");
  const auto out = temp_dir("glb-parts") / "robot.glb";
  const auto r = run_skelcd({"export", robot.string(), "--frame", "0", "-o", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto original = skelcd::skinning::import_rig(robot).rig.mesh.part_names;
  // Read back through assimp: a glTF mesh with several primitives would come back as several
  // meshes all named after it; one glTF mesh per part comes back named as the parts.
  const auto exported = skelcd::skinning::import_rig(out).rig.mesh.part_names;
  EXPECT_EQ(exported.size(), original.size());
  EXPECT_EQ(
      std::multiset<std::string>(exported.begin(), exported.end()),
      std::multiset<std::string>(original.begin(), original.end()));
  // The glTF JSON chunk names each mesh once.
  const std::string bytes = read_text(out);
  EXPECT_EQ(occurrences(bytes, "\"primitives\""), original.size());
}

// --- 4. the disk fills up during a check --------------------------------------------------

TEST(BadInputCli, AFullDiskIsOneLineAndTheRowsWrittenStayReadable) {
  // A 60 KiB tmpfs in a mount namespace of our own (unshare -rm: no privileges needed).
  const auto dir = temp_dir("disk-full");
  const auto mount_point = dir / "small";
  std::filesystem::create_directories(mount_point);
  const auto log = mount_point / "run.h5";
  const auto err = dir / "err.txt";
  const auto readable = dir / "readable.txt";
  // Under AddressSanitizer the check runs without leak detection: libhdf5 keeps the buffer of
  // the write that failed (40 KB, allocated and lost inside the library), which is not ours.
  const std::string script = "mount -t tmpfs -o size=60k none '" + mount_point.string() +
                             "' && ASAN_OPTIONS=detect_leaks=0 '" + SKELCD_EXE + "' check '" +
                             asset("characters/CesiumMan.glb").string() +
                             "' --method bvh --threads 1 -o '" + log.string() +
                             "' > /dev/null 2> '" + err.string() + "'; echo \\$? > '" +
                             dir.string() + "/rc'; '" + SKELCD_EXE + "' inspect --csv '" +
                             log.string() + "' > '" + readable.string() + "' 2>&1";
  const std::string command = "unshare -rm sh -c \"" + script + "\"";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  EXPECT_EQ(read_text(dir / "rc"), "1\n");
  const std::string message = read_text(err);
  EXPECT_EQ(count_lines(message), 1u) << message;
  EXPECT_EQ(
      message.rfind(
          "skelcd: " + log.string() + ": the disk is full (No space left on device); its first ",
          0),
      0u)
      << message;
  EXPECT_NE(message.find("were written and are readable"), std::string::npos) << message;
  EXPECT_EQ(message.find("18446744073709551615"), std::string::npos);
  // What it says was written is what inspect reads back in the same namespace.
  const std::string csv = read_text(readable);
  EXPECT_NE(csv.find(log.string() + ","), std::string::npos) << csv;
  const auto rows_at = message.find("its first ") + 10;
  const std::string rows = message.substr(rows_at, message.find(' ', rows_at) - rows_at);
  EXPECT_NE(csv.find("no (" + rows + "/"), std::string::npos)
      << "message: " << message << "\ncsv: " << csv;

  // With the default method the disk fills while the first rows are set up: still one line and
  // exit 1 — libhdf5's exit handler used to crash on the file whose close had failed (SIGSEGV).
  const auto small_rc = dir / "rc-default";
  const std::string again = "unshare -rm sh -c \"mount -t tmpfs -o size=60k none '" +
                            mount_point.string() + "' && ASAN_OPTIONS=detect_leaks=0 '" +
                            SKELCD_EXE + "' check '" + asset("characters/CesiumMan.glb").string() +
                            "' --threads 1 -o '" + log.string() + "' > /dev/null 2> '" +
                            err.string() + "'; echo \\$? > '" + small_rc.string() + "'\"";
  ASSERT_EQ(std::system(again.c_str()), 0) << again;
  EXPECT_EQ(read_text(small_rc), "1\n");
  EXPECT_EQ(count_lines(read_text(err)), 1u) << read_text(err);
}

// --- 13. a long exact query shows progress on a terminal ------------------------------------

TEST(BadInputCli, ALongExactQueryShowsElementaryTestsOnATerminal) {
  // `script` gives the run a terminal. The funnel step there and back, three times (links to
  // its two frames): three intervals of ~0.35 s each exactly, 2026-12-01, on this machine.
  const auto dir = temp_dir("progress");
  const auto frames = dir / "frames";
  std::filesystem::create_directories(frames);
  for (int i = 0; i < 4; ++i) {
    const auto target = asset("cloth-funnel/frames") / (i % 2 == 0 ? "227.ply" : "228.ply");
    std::string name = std::to_string(i);
    name.append(".ply");
    std::filesystem::create_symlink(std::filesystem::absolute(target), frames / name);
  }
  const auto out = dir / "tty.txt";
  const std::string command =
      "script -qfec \"'" + std::string(SKELCD_EXE) + "' check '" + frames.string() +
      "' --accuracy exact --threads 1 --query ccd\" /dev/null > '" + out.string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const std::string tty = read_text(out);
  // At least one redraw while a row was not done yet, with tests counted.
  EXPECT_NE(tty.find("/3 ("), std::string::npos) << tty.substr(0, 400);
  EXPECT_NE(tty.find(" elementary tests"), std::string::npos) << tty.substr(0, 400);
  // Without a terminal, nothing of it.
  const auto plain = run_skelcd(
      {"check", asset("cloth-funnel/frames").string(), "--query", "ccd", "--threads", "1"});
  EXPECT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_EQ(plain.err, "");
}

}  // namespace
