// The import's child process sends its rig back (skinning/detail/imported_rig_stream.hpp): an
// isolated import is exactly a direct import, field by field and bit for bit, for every bundled
// character, a few of assimp's test models and a 100k-triangle mesh; a damaged answer (cut short,
// a count that lies, bytes flipped, bytes after the end) is an IoError naming the file, never a
// crash or a huge allocation.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "skinning/assimp_import.hpp"
#include "skinning/detail/import_guard.hpp"
#include "skinning/detail/imported_rig_stream.hpp"
#include "skinning/errors.hpp"
#include "tests/skinning/mini_rigs.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::skinning {
namespace {

using skelcd::test::asset;
using skelcd::test::assimp_model;
using skelcd::test::temp_dir;

// Collects every field that differs between two imported rigs; doubles compare by their bits
// (so -0 differs from 0, and a NaN equals only the same NaN).
class Differences {
 public:
  void bits(const std::string& what, const void* a, const void* b, std::size_t bytes) {
    if (bytes > 0 && std::memcmp(a, b, bytes) != 0) add(what);
  }
  void value(const std::string& what, double a, double b) { bits(what, &a, &b, sizeof a); }
  void affine(const std::string& what, const Eigen::Affine3d& a, const Eigen::Affine3d& b) {
    bits(what, a.matrix().data(), b.matrix().data(), sizeof(double) * 16);
  }
  void vector3(const std::string& what, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    bits(what, a.data(), b.data(), sizeof(double) * 3);
  }
  template <class T>
  void same(const std::string& what, const T& a, const T& b) {
    if (!(a == b)) add(what);
  }
  // Vectors of doubles or of fixed-size Eigen objects: the size, then the bits.
  template <class T>
  void array(const std::string& what, const std::vector<T>& a, const std::vector<T>& b) {
    if (a.size() != b.size()) return add(what + " (size)");
    bits(what, a.data(), b.data(), a.size() * sizeof(T));
  }
  // Sizes first, so that a loop over both may stop at the shorter.
  template <class N>
  bool sizes(const std::string& what, N a, N b) {
    if (a == b) return true;
    add(what + " (size " + std::to_string(a) + " vs " + std::to_string(b) + ")");
    return false;
  }

  ::testing::AssertionResult result() const {
    if (list_.empty()) return ::testing::AssertionSuccess();
    auto failure = ::testing::AssertionFailure() << list_.size() << " fields differ:";
    for (std::size_t i = 0; i < list_.size() && i < 20; ++i) failure << "\n  " << list_[i];
    return failure;
  }

 private:
  void add(const std::string& what) { list_.push_back(what); }
  std::vector<std::string> list_;
};

void compare_mesh(Differences& d, const Mesh& a, const Mesh& b) {
  if (d.sizes("rest_positions", a.rest_positions.rows(), b.rest_positions.rows()))
    d.bits(
        "rest_positions",
        a.rest_positions.data(),
        b.rest_positions.data(),
        sizeof(double) * static_cast<std::size_t>(a.rest_positions.size()));
  if (d.sizes("triangles", a.triangles.rows(), b.triangles.rows()))
    d.bits(
        "triangles",
        a.triangles.data(),
        b.triangles.data(),
        sizeof(std::int32_t) * static_cast<std::size_t>(a.triangles.size()));
  d.same("face_part", a.face_part, b.face_part);
  d.same("face_index_in_part", a.face_index_in_part, b.face_index_in_part);
  d.same("vertex_part", a.vertex_part, b.vertex_part);
  d.same("vertex_index_in_part", a.vertex_index_in_part, b.vertex_index_in_part);
  d.same("part_names", a.part_names, b.part_names);
  d.same("excluded_part_pairs", a.excluded_part_pairs, b.excluded_part_pairs);
}

void compare_skeleton(Differences& d, const Skeleton& a, const Skeleton& b) {
  if (d.sizes("nodes", a.nodes.size(), b.nodes.size())) {
    for (std::size_t n = 0; n < a.nodes.size(); ++n) {
      const std::string at = "node " + std::to_string(n);
      d.same(at + " name", a.nodes[n].name, b.nodes[n].name);
      d.same(at + " parent", a.nodes[n].parent, b.nodes[n].parent);
      d.affine(at + " rest_local", a.nodes[n].rest_local, b.nodes[n].rest_local);
    }
  }
  if (d.sizes("bones", a.bones.size(), b.bones.size())) {
    for (std::size_t i = 0; i < a.bones.size(); ++i) {
      const std::string at = "bone " + std::to_string(i);
      d.same(at + " name", a.bones[i].name, b.bones[i].name);
      d.same(at + " node", a.bones[i].node, b.bones[i].node);
      d.same(at + " parent", a.bones[i].parent, b.bones[i].parent);
      d.affine(at + " inverse_bind", a.bones[i].inverse_bind, b.bones[i].inverse_bind);
      d.vector3(at + " rest_head", a.bones[i].rest_head, b.bones[i].rest_head);
      d.vector3(at + " rest_tail", a.bones[i].rest_tail, b.bones[i].rest_tail);
    }
  }
  d.affine("root_transform", a.root_transform, b.root_transform);
}

void compare_weights(Differences& d, const SkinWeights& a, const SkinWeights& b) {
  d.same("weights rows", a.rows(), b.rows());
  d.same("weights cols", a.cols(), b.cols());
  d.same("weights compressed", a.isCompressed(), b.isCompressed());
  if (!d.sizes(
          "weights nonzeros",
          static_cast<std::size_t>(a.nonZeros()),
          static_cast<std::size_t>(b.nonZeros())) ||
      a.rows() != b.rows() || !a.isCompressed() || !b.isCompressed())
    return;
  using Index = SkinWeights::StorageIndex;
  const auto rows = static_cast<std::size_t>(a.rows());
  const auto nonzeros = static_cast<std::size_t>(a.nonZeros());
  d.bits("weights row starts", a.outerIndexPtr(), b.outerIndexPtr(), (rows + 1) * sizeof(Index));
  d.bits("weights columns", a.innerIndexPtr(), b.innerIndexPtr(), nonzeros * sizeof(Index));
  d.bits("weights values", a.valuePtr(), b.valuePtr(), nonzeros * sizeof(double));
}

void compare_clip(Differences& d, const std::string& at, const Clip& a, const Clip& b) {
  d.same(at + " name", a.name, b.name);
  d.value(at + " duration_s", a.duration_s, b.duration_s);
  if (d.sizes(at + " channels", a.channels.size(), b.channels.size())) {
    for (std::size_t c = 0; c < a.channels.size(); ++c) {
      const std::string ch = at + " channel " + std::to_string(c);
      const Channel& x = a.channels[c];
      const Channel& y = b.channels[c];
      d.same(ch + " node", x.node, y.node);
      d.array(ch + " translation_times", x.translation_times, y.translation_times);
      d.array(ch + " translations", x.translations, y.translations);
      d.array(ch + " rotation_times", x.rotation_times, y.rotation_times);
      d.array(ch + " rotations", x.rotations, y.rotations);
      d.array(ch + " scale_times", x.scale_times, y.scale_times);
      d.array(ch + " scales", x.scales, y.scales);
    }
  }
  d.array(at + " key_times", a.key_times, b.key_times);
  d.value(at + " frame_rate_hz", a.frame_rate_hz, b.frame_rate_hz);
  d.same(at + " frame_rate_source", a.frame_rate_source, b.frame_rate_source);
}

::testing::AssertionResult same_imported_rig(const ImportedRig& a, const ImportedRig& b) {
  Differences d;
  compare_mesh(d, a.rig.mesh, b.rig.mesh);
  compare_skeleton(d, a.rig.skeleton, b.rig.skeleton);
  compare_weights(d, a.rig.weights, b.rig.weights);
  if (d.sizes("clips", a.rig.clips.size(), b.rig.clips.size())) {
    for (std::size_t c = 0; c < a.rig.clips.size(); ++c)
      compare_clip(d, "clip " + std::to_string(c), a.rig.clips[c], b.rig.clips[c]);
  }
  d.same("source", a.rig.source, b.rig.source);
  if (d.sizes("part_attachments", a.rig.part_attachments.size(), b.rig.part_attachments.size())) {
    for (std::size_t p = 0; p < a.rig.part_attachments.size(); ++p) {
      const std::string at = "part_attachment " + std::to_string(p);
      d.same(at + " node", a.rig.part_attachments[p].node, b.rig.part_attachments[p].node);
      d.affine(
          at + " inverse_bind",
          a.rig.part_attachments[p].inverse_bind,
          b.rig.part_attachments[p].inverse_bind);
    }
  }
  if (d.sizes("refused_clips", a.refused_clips.size(), b.refused_clips.size())) {
    for (std::size_t c = 0; c < a.refused_clips.size(); ++c) {
      d.same("refused clip name", a.refused_clips[c].name, b.refused_clips[c].name);
      d.same("refused clip reason", a.refused_clips[c].reason, b.refused_clips[c].reason);
    }
  }
  d.same("problems", a.problems, b.problems);
  d.value("unit_scale", a.unit_scale, b.unit_scale);
  d.value("rest_pose_deviation", a.rest_pose_deviation, b.rest_pose_deviation);
  return d.result();
}

// --- an isolated import is a direct import ------------------------------------------------

ImportedRig import_with(const std::filesystem::path& file, bool isolate) {
  ImportOptions options;
  options.isolate = isolate;
  return import_rig(file, options);
}

class IsolatedImport : public ::testing::TestWithParam<std::string> {};

std::filesystem::path model(const std::string& file) {
  return file.rfind("assets/", 0) == 0 ? asset(file.substr(7)) : assimp_model(file);
}

TEST_P(IsolatedImport, IsADirectImportBitForBit) {
  const auto file = model(GetParam());
  const auto isolated = import_with(file, true);
  const auto direct = import_with(file, false);
  EXPECT_TRUE(same_imported_rig(isolated, direct));
  EXPECT_GT(isolated.rig.mesh.num_triangles(), 0);
}

INSTANTIATE_TEST_SUITE_P(
    Characters,
    IsolatedImport,
    ::testing::Values(
        // Ours: skinned glTF with clips, an OGRE mesh with its skeleton, Collada with problems.
        "assets/characters/CesiumMan.glb",
        "assets/characters/Fox.glb",
        "assets/characters/RiggedFigure.glb",
        "assets/characters/RobotExpressive.glb",
        "assets/characters/ninja/ninja.mesh",
        "assets/characters/stormtrooper/stormtrooper.dae",
        // Debian's assimp-testmodels: X, FBX (unit scale), glTF, ASE, MD5, unskinned OBJ.
        "X/BCN_Epileptic.X",
        "X/Testwuson.X",
        "FBX/animation_with_skeleton.fbx",
        "glTF2/simple_skin/simple_skin.gltf",
        "ASE/MotionCaptureROM.ase",
        "MD5/SimpleCube.md5mesh",
        "OBJ/spider.obj",
        "OBJ/testmixed.obj"));

TEST(IsolatedImport, ALargeMeshIsADirectImport) {
  // 2 × 240 × 240 = 115,200 triangles: an answer of several MB, far beyond a pipe's buffer.
  const auto file = temp_dir("isolated_large") / "grid.obj";
  {
    std::ofstream out(file);
    constexpr int kN = 240;
    for (int j = 0; j <= kN; ++j) {
      for (int i = 0; i <= kN; ++i)
        out << "v " << i * 0.01 << ' ' << j * 0.01 << ' ' << (i * j) % 7 * 1e-3 << '\n';
    }
    for (int j = 0; j < kN; ++j) {
      for (int i = 0; i < kN; ++i) {
        const int v = j * (kN + 1) + i + 1;
        out << "f " << v << ' ' << v + 1 << ' ' << v + kN + 2 << '\n';
        out << "f " << v << ' ' << v + kN + 2 << ' ' << v + kN + 1 << '\n';
      }
    }
  }
  const auto isolated = import_with(file, true);
  const auto direct = import_with(file, false);
  EXPECT_EQ(isolated.rig.mesh.num_triangles(), 115200);
  EXPECT_TRUE(same_imported_rig(isolated, direct));
}

// --- the stream itself ----------------------------------------------------------------------

// A rig with every field set (none left at its default), as the child would send it.
ImportedRig everything() {
  ImportedRig out;
  out.rig = skinning::test::two_bone_rig();
  out.rig.source = "everything.glb";
  // Rows whose columns increase across the last two rows: a damaged start of the last row then
  // sends a careless check of the columns past their end.
  std::vector<Eigen::Triplet<double>> w{
      {0, 1, 1.0}, {1, 0, 0.5}, {1, 1, 0.5}, {2, 0, 1.0}, {3, 1, 1.0}};
  out.rig.weights.setFromTriplets(w.begin(), w.end());
  out.rig.weights.makeCompressed();
  out.rig.mesh.excluded_part_pairs = {{0, 0}};
  out.rig.skeleton.root_transform = Eigen::Scaling(0.01);
  out.rig.part_attachments = {
      {.node = 1, .inverse_bind = Eigen::Affine3d(Eigen::Translation3d(-1, 0, 0))}};
  Clip& clip = out.rig.clips.front();
  clip.frame_rate_hz = 24.0;
  clip.frame_rate_source = FrameRateSource::key_grid;
  Channel& ch = clip.channels.front();
  ch.translation_times = {0.0, 0.5};
  ch.translations = {{1, 0, 0}, {1, 0.25, -0.0}};
  ch.scale_times = {1.0};
  ch.scales = {{1, 1, 1.5}};
  out.refused_clips = {
      {"broken", "node 'elbow', rotation key 1 (t = 0.2 s) is earlier than key 0"}};
  out.problems = {"clip 'broken' refused: …", "assimp: a warning", ""};
  out.unit_scale = 0.01;
  out.rest_pose_deviation = 3e-7;
  return out;
}

std::vector<char> to_bytes(const ImportedRig& imported) {
  std::vector<char> bytes;
  detail::write_imported_rig(imported, [&](const void* data, std::size_t size) {
    const char* p = static_cast<const char*>(data);
    bytes.insert(bytes.end(), p, p + size);
  });
  return bytes;
}

// Hands `bytes` over in pieces of `piece` bytes, as the pipe does.
ImportedRig from_bytes(const std::vector<char>& bytes, std::size_t piece = 4096) {
  detail::ChildAnswer answer;
  for (std::size_t at = 0; at < bytes.size(); at += piece) {
    const auto end = std::min(bytes.size(), at + piece);
    answer.append(std::vector<char>(
        bytes.begin() + static_cast<std::ptrdiff_t>(at),
        bytes.begin() + static_cast<std::ptrdiff_t>(end)));
  }
  return detail::read_imported_rig(answer, "model.glb");
}

TEST(ImportedRigStream, EveryFieldComesBack) {
  const auto sent = everything();
  for (const std::size_t piece : {std::size_t{1}, std::size_t{7}, std::size_t{4096}}) {
    EXPECT_TRUE(same_imported_rig(from_bytes(to_bytes(sent), piece), sent))
        << "pieces of " << piece;
  }
}

TEST(ImportedRigStream, TheComparisonSeesAChangeInAnyField) {
  // The comparison the isolated-import tests rely on: a sample of fields, each changed alone.
  const auto a = everything();
  auto b = a;
  b.rig.mesh.rest_positions(2, 1) = std::nextafter(a.rig.mesh.rest_positions(2, 1), 1.0);
  EXPECT_FALSE(same_imported_rig(a, b));
  b = a;
  b.rig.mesh.rest_positions(0, 0) = -0.0;  // was +0.0
  EXPECT_FALSE(same_imported_rig(a, b));
  b = a;
  b.rig.clips.front().channels.front().scales.front().z() = 1.5000000000000002;
  EXPECT_FALSE(same_imported_rig(a, b));
  b = a;
  b.rig.weights.coeffRef(1, 0) = 0.5000000000000001;
  EXPECT_FALSE(same_imported_rig(a, b));
  b = a;
  b.problems.back() = " ";
  EXPECT_FALSE(same_imported_rig(a, b));
  b = a;
  b.rig.skeleton.nodes[1].name = "Elbow";
  EXPECT_FALSE(same_imported_rig(a, b));
}

TEST(ImportedRigStream, AnAnswerCutShortIsAnErrorNamingTheFile) {
  const auto bytes = to_bytes(everything());
  for (std::size_t size = 0; size < bytes.size(); ++size) {
    const std::vector<char> cut(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(size));
    EXPECT_THROW_MESSAGE(
        (void)from_bytes(cut),
        IoError,
        "model.glb: the import's answer from its child process is damaged");
  }
}

TEST(ImportedRigStream, BytesAfterTheRigAreAnError) {
  auto bytes = to_bytes(everything());
  bytes.push_back('\0');
  EXPECT_THROW_MESSAGE((void)from_bytes(bytes), IoError, "1 bytes after the rig");
}

TEST(ImportedRigStream, ACountThatLiesIsRefusedBeforeAnythingIsAllocated) {
  // The vertex count follows the magic and the version: 2^60 vertices would be 27 EB.
  auto bytes = to_bytes(everything());
  const std::uint64_t lie = std::uint64_t{1} << 60;
  std::memcpy(bytes.data() + 8, &lie, sizeof lie);
  EXPECT_THROW_MESSAGE(
      (void)from_bytes(bytes), IoError, "1152921504606846976 vertices announced, but only");
}

// Overwrites 4-byte words of `bytes` (every `stride`-th), each alone, with 0xff bytes and then
// with 0x7f: either the read notices (IoError naming the file) or the word was one whose damage
// neither the layout nor validate_rig can see (a byte of a name, a finite coordinate); it never
// crashes, and never throws anything else. Returns how many were noticed.
std::size_t damage_words(const std::vector<char>& bytes, std::size_t stride) {
  std::size_t noticed = 0;
  for (std::size_t at = 0; at + 4 <= bytes.size(); at += 4 * stride) {
    for (const char fill : {static_cast<char>(0xff), static_cast<char>(0x7f)}) {
      auto damaged = bytes;
      std::memset(damaged.data() + at, fill, 4);
      try {
        (void)from_bytes(damaged);
      } catch (const IoError& e) {
        ++noticed;
        EXPECT_EQ(std::string(e.what()).rfind("model.glb: ", 0), 0u) << e.what();
      }
    }
  }
  return noticed;
}

TEST(ImportedRigStream, ADamagedWordIsAnErrorOrHarmless) {
  // Every word of the rig with every field set (each kind of field, the weights' row starts and
  // columns among them: the sanitizer build caught a read past the columns this way), and every
  // 13th word of a real character's answer (RiggedFigure: 370 vertices, 19 bones, a clip; all of
  // its words take 25 s under the sanitizers).
  EXPECT_GT(damage_words(to_bytes(everything()), 1), 0u);
  EXPECT_GT(
      damage_words(to_bytes(import_with(asset("characters/RiggedFigure.glb"), false)), 13), 0u);
}

}  // namespace
}  // namespace skelcd::skinning
