// Real files and bad files through the importer (issue "Real files and bad files"): float noise in
// transforms, one bad clip among good ones, files that lie about their size, crashes and runaway
// allocations kept in a child process, OBJ vertex numbering, Collada bind shape matrices.

#include <gtest/gtest.h>
#include <poll.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "skinning/assimp_import.hpp"
#include "skinning/detail/import_guard.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;
using skelcd::test::temp_dir;

Eigen::Vector3d extent(const Positions& x) {
  return x.colwise().maxCoeff() - x.colwise().minCoeff();
}

bool any_problem_contains(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& p : problems) {
    if (p.find(text) != std::string::npos) return true;
  }
  return false;
}

// --- 1. float noise in the last row of a transform --------------------------------------------

TEST(ImportRobustness, FloatNoiseInTheLastRowOfATransformIsAccepted) {
  // Both files carry node matrices whose last row is (0, 0, 0, 0.99999988)-like noise from
  // assimp's single-precision products; they were refused as "projective".
  const auto ase = import_rig(assimp_model("ASE/MotionCaptureROM.ase"));
  EXPECT_GT(ase.rig.mesh.num_triangles(), 0);
  EXPECT_EQ(ase.rig.clips.size(), 1u);
  const auto q3s = import_rig(assimp_model("Q3D/WusonOrange.q3s"));
  EXPECT_GT(q3s.rig.mesh.num_triangles(), 0);
}

TEST(ImportRobustness, ARealProjectiveTransformIsStillRefused) {
  // A Collada node whose matrix puts 0.5 * z into w: far beyond float noise.
  const auto dir = temp_dir("projective");
  const auto file = dir / "projective.dae";
  std::ofstream(file) << R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>
  <library_geometries>
    <geometry id="tri" name="tri"><mesh>
      <source id="tri-pos"><float_array id="tri-pos-array" count="9">0 0 0 1 0 0 0 1 0</float_array>
        <technique_common><accessor source="#tri-pos-array" count="3" stride="3">
          <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
        </accessor></technique_common></source>
      <vertices id="tri-vtx"><input semantic="POSITION" source="#tri-pos"/></vertices>
      <triangles count="1"><input semantic="VERTEX" source="#tri-vtx" offset="0"/><p>0 1 2</p></triangles>
    </mesh></geometry>
  </library_geometries>
  <library_visual_scenes>
    <visual_scene id="scene"><node id="n" name="n">
      <matrix>1 0 0 0 0 1 0 0 0 0 1 0 0 0 0.5 1</matrix>
      <instance_geometry url="#tri"/>
    </node></visual_scene>
  </library_visual_scenes>
  <scene><instance_visual_scene url="#scene"/></scene>
</COLLADA>
)";
  EXPECT_THROW_MESSAGE(
      (void)import_rig(file), InvalidInput, "projective transform (last row 0 0 0.5 1");
}

// --- 2. one bad clip does not block the file --------------------------------------------------

TEST(ImportRobustness, TheNinjasBrokenClipsAreRefusedAloneAndTheOthersLoad) {
  const auto file = asset("characters/ninja/ninja.mesh");
  const auto imported = import_rig(file);
  // 20 clips in the file; HighJump and JumpNoHeight have a translation key before the one
  // ahead of it (keys 0.33 s then 0 s; 0.083 s then 0 s).
  ASSERT_EQ(imported.refused_clips.size(), 2u);
  EXPECT_EQ(imported.refused_clips[0].name, "HighJump");
  EXPECT_EQ(imported.refused_clips[1].name, "JumpNoHeight");
  EXPECT_NE(
      imported.refused_clips[0].reason.find("earlier than the key before it"), std::string::npos);
  EXPECT_EQ(imported.rig.clips.size(), 18u);
  EXPECT_TRUE(any_problem_contains(imported.problems, "clip 'HighJump' refused"));
  for (const auto& clip : imported.rig.clips) {
    EXPECT_NE(clip.name, "HighJump");
    EXPECT_TRUE(std::is_sorted(clip.key_times.begin(), clip.key_times.end())) << clip.name;
  }

  // Every sound clip can be asked for; the refused one says why.
  const auto model = load_model(file);
  ASSERT_EQ(model.clips.size(), 18u);
  for (const auto& clip : model.clips) {
    const auto motion = model.motion({.clip = clip.name});
    EXPECT_GT(motion->num_samples(), 0) << clip.name;
  }
  EXPECT_THROW_MESSAGE(
      (void)model.motion({.clip = "HighJump"}),
      InvalidInput,
      "clip 'HighJump' was refused: node 'Joint1'");
  EXPECT_THROW_MESSAGE(
      (void)model.motion({.clip = "NoSuchClip"}), InvalidInput, "no clip named 'NoSuchClip'");
}

TEST(ImportRobustness, AnLwsFileWhoseOnlyClipIsBrokenStillLoadsItsMesh) {
  const auto imported = import_rig(assimp_model("LWS/move_y_pre_ofrep_post_osc.lws"));
  EXPECT_GT(imported.rig.mesh.num_triangles(), 0);
  EXPECT_TRUE(imported.rig.clips.empty());
  ASSERT_EQ(imported.refused_clips.size(), 1u);
  EXPECT_NE(
      imported.refused_clips[0].reason.find("earlier than the key before it"), std::string::npos);
}

// --- 3. files that lie about their size; crashes and memory kept in a child ---------------------

TEST(ImportRobustness, DeclaredCountsBeyondTheFileSizeAreRefusedBeforeImporting) {
  // 309 bytes declaring 353,535,235,358 vertices: assimp itself grows to 15.8 GB on it.
  EXPECT_THROW_MESSAGE(
      (void)import_rig(assimp_model("invalid/OutOfMemory.off")),
      InvalidInput,
      "declares 353535235358 vertices and 6 faces");
  const auto dir = temp_dir("declared");
  const auto ply = dir / "huge.ply";
  std::ofstream(ply, std::ios::binary)
      << "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000\n"
         "property float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      << std::string(64, '\0');
  EXPECT_THROW_MESSAGE(
      (void)import_rig(ply),
      InvalidInput,
      "declares 1000000000 vertex elements and 1 face elements");
  // A sound file of each format passes the check (and imports).
  EXPECT_GT(import_rig(assimp_model("OFF/Cube.off")).rig.mesh.num_triangles(), 0);
  EXPECT_GT(import_rig(assimp_model("PLY/cube_binary.ply")).rig.mesh.num_triangles(), 0);
  EXPECT_GT(import_rig(assimp_model("PLY/cube.ply")).rig.mesh.num_triangles(), 0);
}

// assimp's MD5 loader indexes its arrays with the file's numbers unchecked (found by
// fuzz_assimp_import); the check before importing refuses what would send it outside them.
TEST(ImportRobustness, Md5MeshesThatSendAssimpOutsideItsArraysAreRefusedBeforeImporting) {
  const auto cube = assimp_model("MD5/SimpleCube.md5mesh");
  std::string text;
  {
    std::ifstream in(cube, std::ios::binary);
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_NE(text.find("vert 16 ( -0.25 -0.5 ) 14 2"), std::string::npos);
  const auto dir = temp_dir("md5");
  int n = 0;
  const auto damaged = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at != std::string::npos) t.replace(at, from.size(), to);
    const auto file = dir / ("damaged" + std::to_string(++n) + ".md5mesh");
    std::ofstream(file, std::ios::binary) << t;
    return file;
  };
  const auto refused = [](const std::filesystem::path& file, const std::string& message) {
    EXPECT_THROW_MESSAGE(
        detail::check_declared_counts(file), InvalidInput, file.string() + ": " + message);
  };
  // The sound file passes the check and imports.
  detail::check_declared_counts(cube);
  EXPECT_GT(import_rig(cube).rig.mesh.num_triangles(), 0);

  refused(
      damaged("vert 16 ( -0.25 -0.5 ) 14 2", "vert 16 ( -0.25 -0.5 ) 76 2"),
      "MD5 mesh 1 (line 13): vertex 16 uses weights 76 to 77, but the mesh has 16 weights");
  refused(
      damaged("weight 3 2 ", "weight 3 7 "),
      "MD5 mesh 1 (line 13): weight 3 names joint 7, but the file has 3 joints");
  refused(
      damaged("tri 11 22 20 23\n", ""),
      "MD5 mesh 1 (line 13) declares 12 triangles but gives no `tri` line for triangle 11");
  refused(
      damaged("tri 9 18 16 19", "tri 9 18 16 24"),
      "MD5 mesh 1 (line 13): triangle 9 uses vertex 24, but the mesh has 24 vertices");
  refused(
      damaged("numverts 24", "numverts 25"), "MD5 mesh 1 (line 13): vertex 24 is in no triangle");
  // A NUL ends assimp's reading of the mesh (the triangles after it are never given).
  refused(
      damaged("tri 10 22 21 20", std::string("tri 10 22 21 20\0", 16)),
      "MD5 mesh 1 (line 13) declares 12 triangles but gives no `tri` line for triangle 11");
  refused(
      damaged("vert 3 ( 0.1875 0.25 ) 6 2", "vert 3 ( 0.1875 0.25 6 2"),
      "MD5 line 21 is not `vert");
  // A quote with no partner: assimp's comment remover reads on past the end of the text.
  refused(
      damaged("weight 15 2 0.5 ( 31.9750270844 0.0196647644 -32 )\n}", "weight 15 2 \""),
      "the MD5 text ends where assimp's MD5 reader expects more");
  // A form feed where a section starts: assimp adds empty sections until memory runs out.
  refused(damaged("\nmesh {", "\n\fmesh {"), "MD5 line 13: a form feed where a section starts");
  // The joints a section swallows: "numMeshes 1" directly followed by "joints {" makes the
  // joints the elements of a section named numMeshes, so the file has none.
  refused(
      damaged("numMeshes 1\n\njoints {", "numMeshes 1\njoints {"),
      "MD5 mesh 1 (line 12): weight 0 names joint 1, but the file has 0 joints");
}

TEST(ImportGuard, AnExceptionInTheChildIsRethrownWithItsMessage) {
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 60};
  EXPECT_THROW_MESSAGE(
      detail::run_isolated(
          "model.glb", limits, [] { throw InvalidInput("model.glb: vertex 3 is bad"); }),
      InvalidInput,
      "model.glb: vertex 3 is bad");
  EXPECT_THROW_MESSAGE(
      detail::run_isolated("model.glb", limits, [] { throw IoError("model.glb: cannot read"); }),
      IoError,
      "model.glb: cannot read");
  EXPECT_NO_THROW(detail::run_isolated("model.glb", limits, [] {}));
}

TEST(ImportGuard, ACrashInTheChildIsOneLineAndThisProcessGoesOn) {
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 60};
  EXPECT_THROW_MESSAGE(
      detail::run_isolated("model.glb", limits, [] { std::abort(); }),
      IoError,
      "model.glb: the importer (assimp) crashed reading it (SIGABRT)");
}

TEST(ImportGuard, ARunawayAllocationInTheChildIsRefusedWithTheLimit) {
  const detail::ImportLimits limits{.memory_bytes = std::size_t{256} << 20, .time_s = 60};
  // Grows past the limit a block at a time, touching the memory, as a lying loader does.
  const auto grow = [] {
    std::vector<std::vector<char>> blocks;
    for (int i = 0; i < 64; ++i) blocks.emplace_back(std::size_t{64} << 20, 'x');
  };
  EXPECT_THROW_MESSAGE(
      detail::run_isolated("model.glb", limits, grow),
      InvalidInput,
      "model.glb: importing it needs more memory than the import memory limit of 256 MiB");
}

#if !defined(__SANITIZE_ADDRESS__)  // the sanitizers' allocator has a heap of its own
TEST(ImportGuard, TheChildsHeapIsAdvisedAsHugePagesWithinItsLimit) {
  // The child grows its heap by 30 MiB at once (at most an eighth of its limit) and advises it
  // as transparent huge pages ("hg" in the mapping's VmFlags, whatever the kernel's mode): 8 MiB
  // allocated there and touched is on that mapping. Under a 16 MiB limit (an eighth: 2 MiB) the
  // heap is left as it was, not advised.
  const auto flags_in_child = [](std::size_t limit) {
    const detail::ImportLimits limits{
        .memory_bytes = limit, .time_s = 60, .heap_on_huge_pages = true};
    detail::ChildAnswer answer =
        detail::run_isolated_with_answer("model.glb", limits, [](const detail::AnswerSink& send) {
          constexpr std::size_t kBytes = std::size_t{8} << 20;
          std::vector<char> touched(kBytes, 'x');
          const std::string flags = test::vm_flags_at(touched.data() + kBytes / 2);
          send(flags.data(), flags.size());
        });
    std::string flags(answer.size(), '\0');
    EXPECT_TRUE(answer.read(flags.data(), flags.size()));
    return flags;
  };
  const bool advisable = std::filesystem::exists("/sys/kernel/mm/transparent_hugepage/enabled");
  const std::string large = flags_in_child(std::size_t{1} << 30);
  ASSERT_EQ(large.rfind("VmFlags:", 0), 0u) << large;
  EXPECT_EQ(large.find(" hg") != std::string::npos, advisable) << large;
  const std::string small = flags_in_child(std::size_t{16} << 20);
  ASSERT_EQ(small.rfind("VmFlags:", 0), 0u) << small;
  EXPECT_EQ(small.find(" hg"), std::string::npos) << small;
}
#endif

TEST(ImportGuard, AChildThatTakesTooLongIsStopped) {
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 0.3};
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW_MESSAGE(
      detail::run_isolated(
          "model.glb", limits, [] { std::this_thread::sleep_for(std::chrono::seconds(30)); }),
      IoError,
      "model.glb: importing it took longer than 0.3 s");
  EXPECT_LT(std::chrono::steady_clock::now() - start, std::chrono::seconds(10));
}

TEST(ImportGuard, ThisProcessWorksWhileTheChildImportsAndItsFailureIsNotTheImports) {
  // The child says it has started, then waits for a byte that only this process's work while
  // waiting sends: run before the fork it would find no child (it waits 10 s, then sends all the
  // same), run after the child's end, or not at all, the child would wait for the time limit.
  int started[2];
  int go[2];
  ASSERT_EQ(::pipe(started), 0);
  ASSERT_EQ(::pipe(go), 0);
  const pid_t parent = ::getpid();
  pid_t ran_in = 0;
  bool saw_the_child = false;
  detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 30};
  limits.while_waiting = [&] {
    ran_in = ::getpid();
    pollfd p{started[0], POLLIN, 0};
    char byte = 0;
    saw_the_child = ::poll(&p, 1, 10000) == 1 && ::read(started[0], &byte, 1) == 1 && byte == 's';
    const char value = 42;
    (void)!::write(go[1], &value, 1);
    throw std::runtime_error("work beside the import failed");  // dropped: not the import's
  };
  auto answer =
      detail::run_isolated_with_answer("model.glb", limits, [&](const detail::AnswerSink& send) {
        const char s = 's';
        if (::write(started[1], &s, 1) != 1) throw IoError("model.glb: cannot say it started");
        char value = 0;
        if (::read(go[0], &value, 1) != 1) throw IoError("model.glb: no byte from the parent");
        send(&value, 1);
      });
  for (const int fd : {started[0], started[1], go[0], go[1]}) ::close(fd);
  EXPECT_EQ(ran_in, parent);
  EXPECT_TRUE(saw_the_child);
  ASSERT_EQ(answer.size(), 1u);
  char value = 0;
  ASSERT_TRUE(answer.read(&value, 1));
  EXPECT_EQ(value, 42);
}

// A probe's answer: `blocks` times the same 64 KiB of a pattern, sent as they are made.
void send_blocks(const detail::AnswerSink& send, int blocks) {
  std::vector<char> block(std::size_t{64} << 10);
  for (std::size_t i = 0; i < block.size(); ++i) block[i] = static_cast<char>(i * 31 % 251);
  for (int b = 0; b < blocks; ++b) send(block.data(), block.size());
}

TEST(ImportGuard, AnAnswerFarLargerThanThePipeArrivesWhole) {
  // 32 MiB against a pipe of 64 KiB: the parent reads while the child writes (no deadlock).
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 60};
  auto answer = detail::run_isolated_with_answer(
      "model.glb", limits, [](const detail::AnswerSink& send) { send_blocks(send, 512); });
  ASSERT_EQ(answer.size(), std::size_t{32} << 20);
  std::vector<char> block(std::size_t{64} << 10);
  bool same = true;
  for (int b = 0; b < 512; ++b) {
    ASSERT_TRUE(answer.read(block.data(), block.size()));
    for (std::size_t i = 0; i < block.size(); ++i)
      same = same && block[i] == static_cast<char>(i * 31 % 251);
  }
  EXPECT_TRUE(same);
  EXPECT_EQ(answer.size(), 0u);
}

TEST(ImportGuard, AFailureBeforeTheAnswerIsSentIsReportedAsBefore) {
  // Less than a block sent, then a throw: the answer never left the child, the error does.
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 60};
  EXPECT_THROW_MESSAGE(
      (void)detail::run_isolated_with_answer(
          "model.glb",
          limits,
          [](const detail::AnswerSink& send) {
            send("abc", 3);
            throw InvalidInput("model.glb: vertex 3 is bad");
          }),
      InvalidInput,
      "model.glb: vertex 3 is bad");
}

TEST(ImportGuard, AChildThatCrashesOrFailsWhileAnsweringIsReported) {
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 30, .time_s = 60};
  EXPECT_THROW_MESSAGE(
      (void)detail::run_isolated_with_answer(
          "model.glb",
          limits,
          [](const detail::AnswerSink& send) {
            send_blocks(send, 16);
            std::abort();
          }),
      IoError,
      "model.glb: the importer (assimp) crashed reading it (SIGABRT)");
  EXPECT_THROW_MESSAGE(
      (void)detail::run_isolated_with_answer(
          "model.glb",
          limits,
          [](const detail::AnswerSink& send) {
            send_blocks(send, 16);
            throw IoError("model.glb: too late to say so");
          }),
      IoError,
      "model.glb: the importer (assimp) ended without completing its answer");
}

TEST(ImportGuard, AnAnswerLargerThanTheMemoryLimitIsRefused) {
  // The child's answer is what it held: more than its limit is a child gone wrong, and the
  // parent stops reading there instead of holding it all.
  const detail::ImportLimits limits{.memory_bytes = std::size_t{1} << 20, .time_s = 60};
  EXPECT_THROW_MESSAGE(
      (void)detail::run_isolated_with_answer(
          "model.glb", limits, [](const detail::AnswerSink& send) { send_blocks(send, 1 << 20); }),
      InvalidInput,
      "model.glb: importing it needs more memory than the import memory limit of 1 MiB");
}

// In a process of its own (gtest's "threadsafe" death-test style runs the test binary anew for
// the statement): heap that earlier tests freed in this process is room the import's child
// allocates in without adding address space (import_guard.cpp counts at most the limit of it),
// and after the 28k-triangle CesiumMan copy's import there is more of it than CesiumMan needs.
TEST(ImportRobustness, ATinyImportMemoryLimitRefusesARealCharacter) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        ImportOptions options;
        options.memory_limit_bytes = std::size_t{1} << 20;  // 1 MiB: CesiumMan needs more
        try {
          (void)import_rig(asset("characters/CesiumMan.glb"), options);
        } catch (const InvalidInput& e) {
          std::cerr << e.what() << '\n';
          std::_Exit(0);
        }
        std::_Exit(1);
      },
      ::testing::ExitedWithCode(0),
      "importing it needs more memory than the import memory limit of 1 MiB");
}

// --- what fuzzing found (fuzz/crashes/, docs/fuzzing.md) ------------------------------------

std::filesystem::path fuzz_input(const std::string& relative) {
  return std::filesystem::path(SKELCD_SOURCE_DIR) / "fuzz/crashes" / relative;
}

// One line naming the file, whatever the exception's type (an assimp crash is IoError, a memory
// blow-up InvalidInput; under AddressSanitizer a crash ends the child differently).
void expect_one_line_refusal(const std::filesystem::path& file, const ImportOptions& options = {}) {
  bool refused = false;
  try {
    (void)import_rig(file, options);
  } catch (const std::exception& e) {
    refused = true;
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(file.string() + ": ", 0), 0u) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  }
  EXPECT_TRUE(refused) << file;
}

TEST(ImportRobustness, AFileThatMadeUsUseFreedMemoryImportsCleanly) {
  // A bone naming no node grew the hierarchy's transforms while a reference into them was held.
  const auto imported = import_rig(fuzz_input("ours/add_part_use_after_free.md5mesh"));
  EXPECT_GT(imported.rig.mesh.num_triangles(), 0);
}

TEST(ImportRobustness, FilesOnWhichAssimpCrashesOrRunsAwayAreOneLineEach) {
  for (const char* f :
       {"assimp/md5mesh_null_deref.md5mesh",
        "assimp/md5mesh_weight_out_of_range.md5mesh",
        "assimp/collada_assert_abort.dae",
        "assimp/ply_no_vertex_element_segv.ply",
        "assimp/triangulate_assert_abort.ply",
        "assimp/x_25gb_allocation.x",
        "assimp/x_runaway_allocation.x",
        "assimp/x_compressed_zlib_leak.x"}) {
    SCOPED_TRACE(f);
    expect_one_line_refusal(fuzz_input(f));
  }
  // The PLY reader loops for ever at the end of this file: the child is stopped at the limit.
  ImportOptions quick;
  quick.time_limit_s = 2.0;
  EXPECT_THROW_MESSAGE(
      (void)import_rig(fuzz_input("assimp/ply_reader_endless_loop.ply"), quick),
      IoError,
      "importing it took longer than 2 s");
}

// --- 8. a NaN in an OBJ is named by the file's own vertex number ------------------------------

TEST(ImportRobustness, ANanInAnObjNamesTheFilesVertexNotAssimpsCorner) {
  const auto dir = temp_dir("nan_vertex");
  const auto file = dir / "nan7.obj";
  // Seven vertices, the 7th (0-based 6) is NaN; the faces reach it at corner 8 of assimp's
  // unindexed list (faces 1 2 3, 4 5 6, then 2 4 7).
  std::ofstream(file) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nv 3 0 0\nv 2 1 0\nv 5 nan 0\n"
                         "f 1 2 3\nf 4 5 6\nf 2 4 7\n";
  EXPECT_THROW_MESSAGE(
      (void)import_rig(file),
      InvalidInput,
      file.string() + ": vertex 6 has a non-finite coordinate");
}

// --- 10. the Collada bind shape matrix ------------------------------------------------------

TEST(ImportRobustness, TheStormtroopersBindShapeMatrixStandsItsRestPoseUp) {
  const auto file = asset("characters/stormtrooper/stormtrooper.dae");
  const auto model = load_model(file);
  // Without the bind shape matrix the rest mesh lay along -Z, 2.1 x 0.79 x 3.7, while every
  // posed frame stands ~5.5 tall on +Y; the file's up axis is Y.
  const Eigen::Vector3d rest = extent(model.mesh->rest_positions);
  EXPECT_GT(rest.y(), rest.x());
  EXPECT_GT(rest.y(), rest.z());
  EXPECT_GT(rest.y(), 5.0);
  const auto motion = model.motion();
  Positions x;
  motion->positions(0, x);
  const Eigen::Vector3d posed = extent(x);
  EXPECT_NEAR(posed.y(), 5.49, 0.05);  // posing never depended on it: the offsets carried it
  EXPECT_GT(posed.y(), posed.x());
  // The rest and posed meshes now share one frame: the feet stay near y = 0 in both.
  EXPECT_NEAR(model.mesh->rest_positions.col(1).minCoeff(), x.col(1).minCoeff(), 0.1);
  EXPECT_LT(model.rest_pose_deviation, 0.25 * rest.norm());  // was 170 %
}

// --- 12. nothing of assimp's own printing reaches our streams ---------------------------------

TEST(ImportRobustness, AssimpPrintingToStdoutIsCapturedAsAProblem) {
  // OpenGEX's DDL parser prints "nullptr returned by creating DDLNode." to stdout.
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_THROW((void)import_rig(assimp_model("OpenGEX/empty_camera.ogex")), IoError);
  const auto out = testing::internal::GetCapturedStdout();
  const auto err = testing::internal::GetCapturedStderr();
  EXPECT_EQ(out, "");
  EXPECT_EQ(err, "");
}

}  // namespace
}  // namespace skelcd::skinning
