#include "skinning/assimp_import.hpp"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <assimp/DefaultLogger.hpp>
#include <assimp/Importer.hpp>
#include <assimp/LogStream.hpp>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <mutex>
#include <new>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "skinning/detail/collada_bind_shape.hpp"
#include "skinning/detail/import_guard.hpp"
#include "skinning/detail/imported_rig_stream.hpp"
#include "skinning/errors.hpp"
#include "skinning/frame_sequence.hpp"

namespace skelcd::skinning {
namespace {

// Weights are stored in single precision and exporters round them; a row whose sum is off by
// less than this is not worth a line in the problem list (it is normalised all the same).
constexpr double kWeightSumReportTolerance = 1e-4;
// A skinned mesh is placed in the scene frame instead of its node's frame only when the scene
// frame reproduces the file's rest pose to this fraction of the mesh's size: single-precision
// files agree to ~1e-6, files whose rest pose is not their bind pose miss by a sizeable part of it.
constexpr double kBindFrameEvidence = 1e-3;
// Assimp warnings repeated in the problem list, at most (the rest are counted).
constexpr std::size_t kMaxForwardedWarnings = 8;
// How far the last row of a node or offset matrix may be from (0, 0, 0, 1) and still count as
// affine: 64 units of float rounding (2^-24 each, ~3.8e-6). assimp's loaders build matrices in
// float through a few products or an inverse, each adding a few ulps; a projective matrix
// (a camera's, a shear into w) is off by orders of magnitude more.
constexpr double kAffineRowTolerance = 64.0 * 0x1p-24;
// Ticks per second assimp's loaders assume when a file does not say (aiAnimation docs).
constexpr double kDefaultTicksPerSecond = 25.0;
// A frame rate the file declares above this is ignored (FBX's highest time mode is 1000 fps).
constexpr double kMaxFileFrameRateHz = 1000.0;

// ---------------------------------------------------------------------------------------------
// assimp's logger is a process-wide singleton: imports are serialised, and each one listens to
// warnings and errors through its own stream while it runs.

std::mutex& import_mutex() {
  static std::mutex m;
  return m;
}

class CollectingStream final : public Assimp::LogStream {
 public:
  void write(const char* message) override {
    std::string line(message);
    // DefaultLogger prefixes "Warn,  T0: " and appends a newline.
    if (const auto colon = line.find(": "); colon != std::string::npos && colon < 16)
      line.erase(0, colon + 2);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    lines.push_back(std::move(line));
  }
  std::vector<std::string> lines;
};

class ScopedLogCapture {
 public:
  ScopedLogCapture() {
    if (Assimp::DefaultLogger::isNullLogger()) {
      Assimp::DefaultLogger::create("", Assimp::Logger::NORMAL, 0);  // no file, no console
    }
    Assimp::DefaultLogger::get()->attachStream(
        &stream_, Assimp::Logger::Warn | Assimp::Logger::Err);
  }
  ~ScopedLogCapture() {
    // Detaching hands ownership of the stream back to us (assimp does not delete it).
    Assimp::DefaultLogger::get()->detachStream(
        &stream_, Assimp::Logger::Warn | Assimp::Logger::Err);
  }
  ScopedLogCapture(const ScopedLogCapture&) = delete;
  ScopedLogCapture& operator=(const ScopedLogCapture&) = delete;
  [[nodiscard]] const std::vector<std::string>& lines() const { return stream_.lines; }

 private:
  CollectingStream stream_;
};

// Some of assimp's parsers print straight to stdout or stderr (OpenGEX's DDL parser: "nullptr
// returned by creating DDLNode."), which would land before our one-line error, or inside a mesh
// written to standard output. While it reads, both descriptors point at a temporary file; what
// was printed becomes problem lines. The import mutex is held, so no other import interleaves.
class ScopedStdCapture {
 public:
  ScopedStdCapture() {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    file_ = std::tmpfile();
    if (file_ == nullptr) return;
    saved_out_ = ::dup(STDOUT_FILENO);
    saved_err_ = ::dup(STDERR_FILENO);
    if (saved_out_ < 0 || saved_err_ < 0 || ::dup2(::fileno(file_), STDOUT_FILENO) < 0 ||
        ::dup2(::fileno(file_), STDERR_FILENO) < 0) {
      restore();
    }
  }
  ~ScopedStdCapture() { restore(); }
  ScopedStdCapture(const ScopedStdCapture&) = delete;
  ScopedStdCapture& operator=(const ScopedStdCapture&) = delete;

  /// Restores stdout and stderr and returns the non-empty lines printed meanwhile (at most 64 KiB).
  std::vector<std::string> finish() {
    restore();
    std::vector<std::string> lines;
    if (file_ == nullptr) return lines;
    std::rewind(file_);
    std::string text(64 * 1024, '\0');
    text.resize(std::fread(text.data(), 1, text.size(), file_));
    std::fclose(file_);
    file_ = nullptr;
    std::size_t start = 0;
    while (start < text.size()) {
      auto end = text.find_first_of("\r\n", start);
      if (end == std::string::npos) end = text.size();
      if (end > start) lines.push_back(text.substr(start, end - start));
      start = end + 1;
    }
    return lines;
  }

 private:
  void restore() {
    std::cout.flush();
    std::cerr.flush();
    std::fflush(nullptr);
    if (saved_out_ >= 0) {
      ::dup2(saved_out_, STDOUT_FILENO);
      ::close(saved_out_);
      saved_out_ = -1;
    }
    if (saved_err_ >= 0) {
      ::dup2(saved_err_, STDERR_FILENO);
      ::close(saved_err_);
      saved_err_ = -1;
    }
  }
  std::FILE* file_ = nullptr;
  int saved_out_ = -1;
  int saved_err_ = -1;
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  return s;
}

// ---------------------------------------------------------------------------------------------

struct Context {
  std::string file;
  std::vector<std::string> problems;
  std::map<std::string, std::size_t> shared_names;  // node name → number of nodes with it
  std::vector<std::string> clips_with_mesh_channels;
  /// Collada bind shape matrices by geometry id and name (detail/collada_bind_shape.hpp).
  std::map<std::string, Eigen::Affine3d> bind_shapes;
  /// Frames per second the file declares for its clips (file_frame_rate), 0 when it declares none.
  double frame_rate_hz = 0.0;
  [[noreturn]] void invalid(const std::string& fault) const {
    throw InvalidInput(file + ": " + fault);
  }
};

Eigen::Affine3d to_affine(const aiMatrix4x4& m, const Context& ctx, const std::string& what) {
  Eigen::Matrix4d e;
  for (unsigned r = 0; r < 4; ++r) {
    for (unsigned c = 0; c < 4; ++c) e(r, c) = static_cast<double>(m[r][c]);
  }
  if (!e.allFinite()) ctx.invalid(what + " has a non-finite transform");
  // assimp composes and inverts matrices in single precision, so an affine transform can reach
  // us with a last row such as (0, 0, 0, 0.99999988): 1 - 2^-23, float noise. Every entry of
  // the last row is compared with (0, 0, 0, 1) up to kAffineRowTolerance; within it the row is
  // noise and is set to (0, 0, 0, 1), beyond it the transform is projective and refused.
  const Eigen::RowVector4d affine_row(0.0, 0.0, 0.0, 1.0);
  const double off = (e.row(3) - affine_row).cwiseAbs().maxCoeff();
  if (off > kAffineRowTolerance) {
    char row[128];
    std::snprintf(row, sizeof row, "%.9g %.9g %.9g %.9g", e(3, 0), e(3, 1), e(3, 2), e(3, 3));
    ctx.invalid(what + " has a projective transform (last row " + row + " is not 0 0 0 1)");
  }
  e.row(3) = affine_row;
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.matrix() = e;
  return a;
}

Eigen::Vector3d to_vector(const aiVector3D& v) {
  return {static_cast<double>(v.x), static_cast<double>(v.y), static_cast<double>(v.z)};
}

std::string node_label(const aiNode* n) { return "node '" + std::string(n->mName.C_Str()) + "'"; }

// Unit scale to metres that the file declares and assimp leaves to the caller.
double file_unit_scale(const aiScene* scene, Context& ctx) {
  const aiMetadata* meta = scene->mMetaData;
  if (meta == nullptr) return 1.0;
  aiString format;
  if (!meta->Get("SourceAsset_Format", format) ||
      lower(format.C_Str()).find("fbx") == std::string::npos)
    return 1.0;
  double factor = 0.0;
  float factor_f = 0.0f;
  if (!meta->Get("UnitScaleFactor", factor)) {
    if (!meta->Get("UnitScaleFactor", factor_f)) return 1.0;
    factor = static_cast<double>(factor_f);
  }
  if (!std::isfinite(factor) || factor <= 0) {
    ctx.problems.push_back(
        "FBX UnitScaleFactor " + std::to_string(factor) + " is not positive; unit scale ignored");
    return 1.0;
  }
  return factor / 100.0;  // FBX units are centimetres times UnitScaleFactor
}

// The frames per second of an FBX time mode (GlobalSettings TimeMode, which assimp's FBX
// converter hands over as the scene metadata "FrameRate"): the table of assimp 5.2's
// FBXConverter::FrameRateToDouble, which also sets every aiAnimation::mTicksPerSecond from it.
// 0 for the default mode (0: no rate chosen, and assimp then counts ticks in seconds) and for
// modes assimp does not know; `custom` for the custom mode (14, CustomFrameRate).
double fbx_time_mode_rate(std::int32_t mode, double custom) {
  switch (mode) {
    case 1:
      return 120.0;
    case 2:
      return 100.0;
    case 3:
      return 60.0;
    case 4:
      return 50.0;
    case 5:
      return 48.0;
    case 6:  // 30
    case 7:  // 30, drop frame
      return 30.0;
    case 8:  // NTSC, drop frame
    case 9:  // NTSC, full frame
      return 29.9700262;
    case 10:  // PAL
      return 25.0;
    case 11:  // cinema
      return 24.0;
    case 12:
      return 1000.0;
    case 13:  // cinema NTSC
      return 23.976;
    case 14:
      return custom;
    default:
      return 0.0;
  }
}

// Frames per second the file declares for its animations, 0 when it declares none. FBX: the time
// mode (fbx_time_mode_rate). Collada: 3ds Max's <frame_rate> extra (detail::read_collada_extras,
// read by the caller into `collada_rate`). Every other format assimp reads (glTF, .X, Ogre, …)
// declares none, or assimp does not hand it over.
double file_frame_rate(const aiScene* scene, double collada_rate, Context& ctx) {
  if (scene->mNumAnimations == 0) return 0.0;
  double rate = collada_rate;
  std::string what = "Collada <frame_rate>";
  const aiMetadata* meta = scene->mMetaData;
  aiString format;
  if (meta != nullptr && meta->Get("SourceAsset_Format", format) &&
      lower(format.C_Str()).find("fbx") != std::string::npos) {
    std::int32_t mode = 0;
    if (!meta->Get("FrameRate", mode)) return 0.0;
    float custom = 0.0f;
    if (!meta->Get("CustomFrameRate", custom)) custom = 0.0f;
    rate = fbx_time_mode_rate(mode, static_cast<double>(custom));
    what = "FBX time mode " + std::to_string(mode);
    if (mode == 14) what += " (custom, CustomFrameRate " + std::to_string(custom) + ")";
    if (mode == 0) return 0.0;
    if (rate == 0.0 && mode != 14) {
      ctx.problems.push_back(what + " is not one assimp knows; the clips' frame rate is not known");
      return 0.0;
    }
  }
  if (rate == 0.0) return 0.0;
  if (!std::isfinite(rate) || rate < 0 || rate > kMaxFileFrameRateHz) {
    ctx.problems.push_back(
        what + " gives " + std::to_string(rate) + " frames per second, not in (0, " +
        std::to_string(static_cast<int>(kMaxFileFrameRateHz)) + "]; ignored");
    return 0.0;
  }
  return rate;
}

// The bind shape of a mesh named after its geometry; assimp appends "_<n>" to the meshes it
// splits one geometry into (one per material).
std::map<std::string, Eigen::Affine3d>::const_iterator find_bind_shape(
    const std::map<std::string, Eigen::Affine3d>& shapes, const std::string& mesh_name) {
  if (const auto it = shapes.find(mesh_name); it != shapes.end()) return it;
  const auto underscore = mesh_name.rfind('_');
  if (underscore == std::string::npos || underscore + 1 == mesh_name.size()) return shapes.end();
  const auto suffix = mesh_name.substr(underscore + 1);
  if (!std::all_of(
          suffix.begin(), suffix.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    return shapes.end();
  return shapes.find(mesh_name.substr(0, underscore));
}

// ---------------------------------------------------------------------------------------------
// The node hierarchy, parents first. assimp builds a tree of pointers; a malformed file (or a
// loader bug) could still make a node reachable twice, which would be a cycle for us.

struct Hierarchy {
  std::vector<const aiNode*> nodes;           // pre-order
  std::vector<Eigen::Affine3d> scene_global;  // without the unit scale
  std::unordered_map<std::string, std::vector<std::int32_t>> by_name;
};

Hierarchy read_hierarchy(const aiScene* scene, Skeleton& skeleton, Context& ctx) {
  Hierarchy h;
  if (scene->mRootNode == nullptr) ctx.invalid("the scene has no root node");
  std::unordered_set<const aiNode*> seen;
  std::vector<std::pair<const aiNode*, std::int32_t>> stack{{scene->mRootNode, -1}};
  // Nodes added later for bones the hierarchy lacks have no aiNode (null entries).
  while (!stack.empty()) {
    const auto [node, parent] = stack.back();
    stack.pop_back();
    if (!seen.insert(node).second)
      ctx.invalid(node_label(node) + " is reached twice in the node hierarchy (a cycle)");
    const auto index = static_cast<std::int32_t>(h.nodes.size());
    h.nodes.push_back(node);
    SkeletonNode sn;
    sn.name = node->mName.C_Str();
    sn.parent = parent;
    sn.rest_local = to_affine(node->mTransformation, ctx, node_label(node));
    h.scene_global.push_back(
        parent < 0 ? sn.rest_local
                   : h.scene_global[static_cast<std::size_t>(parent)] * sn.rest_local);
    h.by_name[sn.name].push_back(index);
    skeleton.nodes.push_back(std::move(sn));
    if (node->mNumChildren > 0 && node->mChildren == nullptr)
      ctx.invalid(node_label(node) + " lists children it does not have");
    for (unsigned c = node->mNumChildren; c-- > 0;) {
      if (node->mChildren[c] == nullptr) ctx.invalid(node_label(node) + " has a null child");
      stack.emplace_back(node->mChildren[c], index);
    }
  }
  return h;
}

// assimp refers to bones' and channels' nodes by name, and names need not be unique (glTF
// allows duplicates; RobotExpressive.glb names a mesh node like the bone above it). Among
// namesakes prefer nodes that already host a bone, then nodes without meshes, then the first.
std::int32_t resolve_node(
    const Hierarchy& h,
    const std::string& name,
    const std::vector<bool>* hosts_bone,
    Context& ctx,
    const std::string& what) {
  const auto it = h.by_name.find(name);
  if (it == h.by_name.end()) return -1;
  const auto& candidates = it->second;
  if (candidates.size() == 1) return candidates.front();
  auto pick = [&](auto&& predicate) -> std::int32_t {
    for (auto c : candidates) {
      if (predicate(c)) return c;
    }
    return -1;
  };
  std::int32_t chosen = -1;
  if (hosts_bone != nullptr)
    chosen = pick([&](std::int32_t c) { return (*hosts_bone)[static_cast<std::size_t>(c)]; });
  if (chosen < 0) {
    chosen = pick([&](std::int32_t c) {
      const aiNode* n = h.nodes[static_cast<std::size_t>(c)];
      return n == nullptr || n->mNumMeshes == 0;
    });
  }
  if (chosen < 0) chosen = candidates.front();
  (void)what;
  ctx.shared_names[name] = candidates.size();
  return chosen;
}

// A root node with a fixed transform, for a bone the hierarchy lacks. Its global (scene space)
// transform is `scene_global`; it has no aiNode.
std::int32_t add_static_node(
    Skeleton& skeleton,
    Hierarchy& h,
    const std::string& name,
    const Eigen::Affine3d& scene_global) {
  const auto index = static_cast<std::int32_t>(skeleton.nodes.size());
  SkeletonNode sn;
  sn.name = name;
  sn.parent = -1;
  sn.rest_local = scene_global;
  skeleton.nodes.push_back(sn);
  h.nodes.push_back(nullptr);
  h.scene_global.push_back(scene_global);
  h.by_name[name].push_back(index);
  return index;
}

// ---------------------------------------------------------------------------------------------

struct PendingBone {
  std::int32_t node;
  Eigen::Affine3d inverse_bind;  // object space
  std::string name;
};

// Two meshes bind one node with "the same" matrix when their object-space inverse binds agree up
// to the rounding of composing them (relative to the largest entry).
constexpr double kSameBindTolerance = 1e-12;

bool same_transform(const Eigen::Affine3d& a, const Eigen::Affine3d& b) {
  const double scale =
      1.0 + std::max(a.matrix().cwiseAbs().maxCoeff(), b.matrix().cwiseAbs().maxCoeff());
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() <= kSameBindTolerance * scale;
}

struct MeshBuild {
  std::vector<Eigen::Vector3d> positions;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<Eigen::Triplet<double>> weights;  // (vertex, pending bone, raw weight)
  std::vector<PendingBone> bones;
  double rest_pose_deviation = 0.0;
};

// One part: its triangles, its vertices placed in object space, and its skin.
void add_part(
    const aiScene* scene,
    const aiMesh* am,
    std::int32_t node,
    Hierarchy& h,
    const Eigen::Affine3d& unit,
    Rig& rig,
    MeshBuild& build,
    Context& ctx) {
  const std::string mesh_name = am->mName.length > 0
                                    ? am->mName.C_Str()
                                    : h.nodes[static_cast<std::size_t>(node)]->mName.C_Str();
  const std::string label = "mesh '" + mesh_name + "'";
  (void)scene;
  if (am->mNumVertices > 0 && am->mVertices == nullptr) ctx.invalid(label + " has no vertex array");
  if (am->mNumFaces > 0 && am->mFaces == nullptr) ctx.invalid(label + " has no face array");

  // Faces: triangles are kept; points and lines (which Triangulate leaves alone) are dropped.
  std::size_t points = 0, lines = 0, triangles = 0;
  for (unsigned f = 0; f < am->mNumFaces; ++f) {
    const aiFace& face = am->mFaces[f];
    if (face.mNumIndices > 0 && face.mIndices == nullptr)
      ctx.invalid(label + ", face " + std::to_string(f) + " has no indices");
    for (unsigned k = 0; k < face.mNumIndices; ++k) {
      if (face.mIndices[k] >= am->mNumVertices) {
        ctx.invalid(
            label + ", face " + std::to_string(f) + " has vertex index " +
            std::to_string(face.mIndices[k]) + " out of range [0, " +
            std::to_string(am->mNumVertices) + ")");
      }
    }
    if (face.mNumIndices == 3)
      ++triangles;
    else if (face.mNumIndices == 2)
      ++lines;
    else if (face.mNumIndices == 1)
      ++points;
    else
      ctx.invalid(
          label + ", face " + std::to_string(f) + " has " + std::to_string(face.mNumIndices) +
          " indices after triangulation");
  }
  if (triangles == 0) {
    ctx.problems.push_back(
        label + " has no triangles (" + std::to_string(points) + " points, " +
        std::to_string(lines) + " lines): skipped");
    return;
  }
  if (points + lines > 0) {
    ctx.problems.push_back(
        label + ": dropped " + std::to_string(points) + " points and " + std::to_string(lines) +
        " lines");
  }
  if (am->mNumAnimMeshes > 0) {
    ctx.problems.push_back(
        label + ": " + std::to_string(am->mNumAnimMeshes) + " morph targets ignored");
  }
  for (unsigned v = 0; v < am->mNumVertices; ++v) {
    if (!to_vector(am->mVertices[v]).allFinite()) {
      ctx.invalid(label + ", vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
  }
  // Vertices in mesh space. A Collada skin's bind shape matrix comes first: assimp 5.2 leaves the
  // vertices as the geometry has them and applies the matrix only inside the offsets, so the
  // rest mesh lay in another frame than every posed one (the stormtrooper lay along -Z).
  Eigen::Affine3d shape = Eigen::Affine3d::Identity();
  if (am->mNumBones > 0) {
    if (const auto it = find_bind_shape(ctx.bind_shapes, mesh_name); it != ctx.bind_shapes.end())
      shape = it->second;
  }
  std::vector<Eigen::Vector3d> local(am->mNumVertices);
  for (unsigned v = 0; v < am->mNumVertices; ++v) local[v] = shape * to_vector(am->mVertices[v]);

  const auto part = static_cast<std::int32_t>(rig.mesh.part_names.size());
  const auto base = static_cast<std::int32_t>(build.positions.size());
  // A copy: add_static_node below grows h.scene_global, which would leave a reference dangling
  // (a use after free that fuzz_assimp_import found).
  const Eigen::Affine3d mesh_global = h.scene_global[static_cast<std::size_t>(node)];

  // Skin: which bind frame B places the mesh? assimp's offset matrices map mesh space to bone
  // space, and a skinned vertex poses as G_bone · offset · v whatever the mesh node says. Files
  // disagree on the frame their bind pose lives in: some store offsets relative to the mesh
  // node (G_rest · offset ≈ mesh node transform: glTF, FBX), others relative to the scene
  // (G_rest · offset ≈ identity: .X). Posing never depends on B (rest = B v and inverse bind =
  // offset · B⁻¹ cancel); B only decides where the bind pose sits. Take the mesh frame unless the
  // file's own rest hierarchy shows it is the scene frame, and report the mismatch that is left.
  Eigen::Affine3d bind_frame = mesh_global;
  std::vector<std::int32_t> bone_node(am->mNumBones, -1);
  std::vector<Eigen::Affine3d> offset(am->mNumBones);
  if (am->mNumBones > 0) {
    if (am->mBones == nullptr) ctx.invalid(label + " lists bones it does not have");
    std::vector<Eigen::Vector3d> skinned(am->mNumVertices, Eigen::Vector3d::Zero());
    std::vector<double> weight_sum(am->mNumVertices, 0.0);
    for (unsigned b = 0; b < am->mNumBones; ++b) {
      const aiBone* bone = am->mBones[b];
      if (bone == nullptr) ctx.invalid(label + " has a null bone " + std::to_string(b));
      const std::string bone_name = bone->mName.C_Str();
      bone_node[b] = resolve_node(h, bone_name, nullptr, ctx, "bone '" + bone_name + "'");
      // assimp folds the bind shape into every offset matrix (offset = inverse bind · shape); the
      // vertices above carry the shape now, so the offsets get it back out.
      offset[b] =
          to_affine(bone->mOffsetMatrix, ctx, label + ", bone '" + bone_name + "' offset matrix") *
          shape.inverse();
      if (bone->mNumWeights > 0 && bone->mWeights == nullptr)
        ctx.invalid(label + ", bone '" + bone_name + "' has no weight array");
      const bool placed = bone_node[b] >= 0;  // a bone without a node says nothing about B
      const Eigen::Affine3d at_rest =
          placed
              ? Eigen::Affine3d(h.scene_global[static_cast<std::size_t>(bone_node[b])] * offset[b])
              : Eigen::Affine3d::Identity();
      for (unsigned k = 0; k < bone->mNumWeights; ++k) {
        const auto& vw = bone->mWeights[k];
        const double w = static_cast<double>(vw.mWeight);
        if (vw.mVertexId >= am->mNumVertices) {
          ctx.invalid(
              label + ", bone '" + bone_name + "' weights vertex " + std::to_string(vw.mVertexId) +
              " out of range [0, " + std::to_string(am->mNumVertices) + ")");
        }
        if (!std::isfinite(w) || w < 0) {
          ctx.invalid(
              label + ", bone '" + bone_name + "' has weight " + std::to_string(w) +
              " for vertex " + std::to_string(vw.mVertexId) + " (must be finite and >= 0)");
        }
        if (w == 0 || !placed) continue;
        skinned[vw.mVertexId] += w * (at_rest * local[vw.mVertexId]);
        weight_sum[vw.mVertexId] += w;
      }
    }
    double dev_mesh = 0.0, dev_scene = 0.0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    for (unsigned v = 0; v < am->mNumVertices; ++v) {
      if (weight_sum[v] <= 0) continue;
      const Eigen::Vector3d p = skinned[v] / weight_sum[v];
      dev_mesh = std::max(dev_mesh, (p - mesh_global * local[v]).norm());
      dev_scene = std::max(dev_scene, (p - local[v]).norm());
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    // assimp's documented convention (the mesh node's frame) unless the file clearly says
    // otherwise: the scene frame reproduces the rest pose to within the file's precision and
    // the mesh frame does not.
    const double extent = (hi - lo).allFinite() ? (hi - lo).norm() : 0.0;
    if (dev_scene < dev_mesh && dev_scene <= kBindFrameEvidence * extent)
      bind_frame = Eigen::Affine3d::Identity();
    const double dev_chosen = bind_frame.matrix() == mesh_global.matrix() ? dev_mesh : dev_scene;
    // A bone whose node is missing (anim_test.x binds 'joint3', which no frame defines) can only
    // stay where the bind pose puts it: a static node of its own at the bind transform
    // B · offset⁻¹ makes its skinning transform the identity in every pose.
    for (unsigned b = 0; b < am->mNumBones; ++b) {
      if (bone_node[b] >= 0) continue;
      const std::string bone_name = am->mBones[b]->mName.C_Str();
      bone_node[b] = add_static_node(rig.skeleton, h, bone_name, bind_frame * offset[b].inverse());
      ctx.problems.push_back(
          label + ": bone '" + bone_name +
          "' names no node of the hierarchy; it stays in its bind pose");
    }
    const double unit_scale = unit.linear()(0, 0);
    build.rest_pose_deviation = std::max(build.rest_pose_deviation, unit_scale * dev_chosen);
  }

  // Vertices in object space.
  const Eigen::Affine3d place = unit * bind_frame;
  for (unsigned v = 0; v < am->mNumVertices; ++v) {
    build.positions.push_back(place * local[v]);
    rig.mesh.vertex_part.push_back(part);
    rig.mesh.vertex_index_in_part.push_back(static_cast<std::int32_t>(v));
  }
  for (unsigned f = 0; f < am->mNumFaces; ++f) {
    const aiFace& face = am->mFaces[f];
    if (face.mNumIndices != 3) continue;
    build.triangles.push_back(
        {base + static_cast<std::int32_t>(face.mIndices[0]),
         base + static_cast<std::int32_t>(face.mIndices[1]),
         base + static_cast<std::int32_t>(face.mIndices[2])});
    rig.mesh.face_part.push_back(part);
    rig.mesh.face_index_in_part.push_back(static_cast<std::int32_t>(f));
  }
  rig.mesh.part_names.push_back(mesh_name);

  // Unweighted vertices follow the mesh node rigidly.
  PartAttachment attachment;
  attachment.node = node;
  attachment.inverse_bind = (unit * mesh_global).inverse();
  rig.part_attachments.push_back(attachment);

  // Bones: one per (node, bind matrix); meshes sharing a skeleton share bones.
  const Eigen::Affine3d to_file = place.inverse();  // object space → mesh space
  std::vector<bool> weighted(am->mNumVertices, false);
  for (unsigned b = 0; b < am->mNumBones; ++b) {
    const aiBone* bone = am->mBones[b];
    const Eigen::Affine3d inverse_bind = offset[b] * to_file;
    std::int32_t index = -1;
    for (std::size_t k = 0; k < build.bones.size(); ++k) {
      if (build.bones[k].node == bone_node[b] &&
          same_transform(build.bones[k].inverse_bind, inverse_bind)) {
        index = static_cast<std::int32_t>(k);
        break;
      }
    }
    if (index < 0) {
      const bool node_taken =
          std::any_of(build.bones.begin(), build.bones.end(), [&](const PendingBone& p) {
            return p.node == bone_node[b];
          });
      if (node_taken) {
        ctx.problems.push_back(
            label + ": bone '" + std::string(bone->mName.C_Str()) +
            "' has a different bind matrix than in another mesh; kept as a separate bone");
      }
      index = static_cast<std::int32_t>(build.bones.size());
      build.bones.push_back({bone_node[b], inverse_bind, bone->mName.C_Str()});
    }
    for (unsigned k = 0; k < bone->mNumWeights; ++k) {
      const auto& vw = bone->mWeights[k];
      if (vw.mWeight > 0) {
        build.weights.emplace_back(
            base + static_cast<int>(vw.mVertexId), index, static_cast<double>(vw.mWeight));
        weighted[vw.mVertexId] = true;
      }
    }
  }
  if (am->mNumBones > 0) {
    const auto unweighted =
        static_cast<std::size_t>(std::count(weighted.begin(), weighted.end(), false));
    if (unweighted > 0) {
      ctx.problems.push_back(
          label + ": " + std::to_string(unweighted) +
          " vertices have no skin weight; they follow the mesh node rigidly");
    }
  }
}

// Bones sorted by node (parents first), weights normalised, bone parents and rest segments.
void finish_skin(MeshBuild& build, const Hierarchy& h, Rig& rig, Context& ctx) {
  std::vector<std::int32_t> order(build.bones.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<std::int32_t>(i);
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return build.bones[static_cast<std::size_t>(a)].node <
           build.bones[static_cast<std::size_t>(b)].node;
  });
  std::vector<std::int32_t> new_index(order.size());
  auto& bones = rig.skeleton.bones;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const auto& p = build.bones[static_cast<std::size_t>(order[k])];
    new_index[static_cast<std::size_t>(order[k])] = static_cast<std::int32_t>(k);
    Bone bone;
    bone.name = p.name;
    bone.node = p.node;
    bone.inverse_bind = p.inverse_bind;
    bones.push_back(bone);
  }
  // Bone hierarchy: nearest ancestor node hosting a bone.
  const auto nn = rig.skeleton.nodes.size();
  std::vector<std::int32_t> bone_of_node(nn, -1);
  for (std::size_t b = 0; b < bones.size(); ++b) {
    auto& slot = bone_of_node[static_cast<std::size_t>(bones[b].node)];
    if (slot < 0) slot = static_cast<std::int32_t>(b);
  }
  for (auto& bone : bones) {
    for (auto n = rig.skeleton.nodes[static_cast<std::size_t>(bone.node)].parent; n >= 0;
         n = rig.skeleton.nodes[static_cast<std::size_t>(n)].parent) {
      if (bone_of_node[static_cast<std::size_t>(n)] >= 0) {
        bone.parent = bone_of_node[static_cast<std::size_t>(n)];
        break;
      }
    }
  }

  // Weights: #V × #B, each non-empty row scaled to sum 1.
  const auto nv = static_cast<Eigen::Index>(build.positions.size());
  for (auto& t : build.weights)
    t = Eigen::Triplet<double>(t.row(), new_index[static_cast<std::size_t>(t.col())], t.value());
  rig.weights.resize(nv, static_cast<Eigen::Index>(bones.size()));
  rig.weights.setFromTriplets(build.weights.begin(), build.weights.end());
  rig.weights.makeCompressed();
  std::size_t off = 0;
  double lowest = 1.0, highest = 1.0;
  for (Eigen::Index v = 0; v < rig.weights.outerSize(); ++v) {
    double sum = 0;
    for (SkinWeights::InnerIterator it(rig.weights, v); it; ++it) sum += it.value();
    if (sum <= 0) continue;
    if (std::abs(sum - 1.0) > kWeightSumReportTolerance) {
      ++off;
      lowest = std::min(lowest, sum);
      highest = std::max(highest, sum);
    }
    for (SkinWeights::InnerIterator it(rig.weights, v); it; ++it) it.valueRef() /= sum;
  }
  if (off > 0) {
    ctx.problems.push_back(
        "skin weights of " + std::to_string(off) + " vertices did not sum to 1 (from " +
        std::to_string(lowest) + " to " + std::to_string(highest) + "); normalised");
  }

  // Rest segments: head at the bone's joint in the bind pose; tail at the mean of its child
  // bones' heads, else of its node's children (e.g. Blender's "_end" nodes) placed in the bind
  // pose, else extended along the bone's own y axis (the glTF/Blender bone direction) by half
  // the distance to its parent's head, or by 5% of the mesh's extent for a lone root bone.
  std::vector<Eigen::Affine3d> bind_global(bones.size());
  for (std::size_t b = 0; b < bones.size(); ++b) {
    bind_global[b] = bones[b].inverse_bind.inverse();
    bones[b].rest_head = bind_global[b].translation();
  }
  double extent = 0.0;
  if (nv > 0) {
    Eigen::Vector3d lo = build.positions.front(), hi = build.positions.front();
    for (const auto& p : build.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    extent = (hi - lo).norm();
  }
  for (std::size_t b = 0; b < bones.size(); ++b) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (const auto& child : bones) {
      if (child.parent == static_cast<std::int32_t>(b) && child.node != bones[b].node) {
        sum += child.rest_head;
        ++count;
      }
    }
    if (count == 0) {
      const aiNode* node = h.nodes[static_cast<std::size_t>(bones[b].node)];
      for (unsigned c = 0; node != nullptr && c < node->mNumChildren; ++c) {
        const auto it = std::find(h.nodes.begin(), h.nodes.end(), node->mChildren[c]);
        const auto child = static_cast<std::size_t>(it - h.nodes.begin());
        if (node->mChildren[c]->mNumMeshes > 0) continue;  // a mesh hanging off the joint
        sum += bind_global[b] * rig.skeleton.nodes[child].rest_local.translation();
        ++count;
      }
    }
    Eigen::Vector3d tail = count > 0 ? Eigen::Vector3d(sum / count) : bones[b].rest_head;
    if ((tail - bones[b].rest_head).norm() == 0.0) {
      double length = 0.05 * extent;
      if (bones[b].parent >= 0) {
        const double to_parent =
            (bones[b].rest_head - bones[static_cast<std::size_t>(bones[b].parent)].rest_head)
                .norm();
        if (to_parent > 0) length = 0.5 * to_parent;
      }
      const Eigen::Vector3d axis = bind_global[b].linear().col(1);
      const double axis_norm = axis.norm();
      tail =
          bones[b].rest_head +
          (axis_norm > 0 ? Eigen::Vector3d(axis / axis_norm) : Eigen::Vector3d::UnitY()) * length;
    }
    bones[b].rest_tail = tail;
  }
}

// ---------------------------------------------------------------------------------------------

// A clip whose data cannot be used (keys out of order, non-finite values, …) is refused alone:
// the rest of the file and its other clips stay usable.
struct ClipRefusal {
  std::string reason;
};

[[noreturn]] void refuse_clip(const std::string& reason) { throw ClipRefusal{reason}; }

// One animation as a clip (channels resolved to nodes, keys in seconds, strictly increasing).
// @throws ClipRefusal when its data are unusable.
Clip read_clip(
    const aiAnimation* anim,
    const std::string& name,
    const Hierarchy& h,
    const std::vector<bool>& hosts_bone,
    Rig& rig,
    Context& ctx) {
  Clip clip;
  clip.name = name;
  const std::string label = "clip '" + clip.name + "'";
  double ticks = anim->mTicksPerSecond;
  if (!std::isfinite(ticks) || ticks <= 0) {
    ticks = kDefaultTicksPerSecond;
    ctx.problems.push_back(
        label + " does not give ticks per second; assumed " +
        std::to_string(static_cast<int>(ticks)));
  }
  if (!std::isfinite(anim->mDuration) || anim->mDuration < 0)
    refuse_clip("its duration is " + std::to_string(anim->mDuration) + " ticks");
  clip.duration_s = anim->mDuration / ticks;
  if (anim->mNumChannels > 0 && anim->mChannels == nullptr)
    refuse_clip("it lists channels it does not have");
  std::vector<bool> animated(rig.skeleton.nodes.size(), false);
  for (unsigned c = 0; c < anim->mNumChannels; ++c) {
    const aiNodeAnim* na = anim->mChannels[c];
    if (na == nullptr) refuse_clip("channel " + std::to_string(c) + " is null");
    const std::string node_name = na->mNodeName.C_Str();
    const auto node =
        resolve_node(h, node_name, &hosts_bone, ctx, label + " channel for '" + node_name + "'");
    if (node < 0) {
      ctx.problems.push_back(label + ": channel for unknown node '" + node_name + "' ignored");
      continue;
    }
    if (animated[static_cast<std::size_t>(node)]) {
      ctx.problems.push_back(label + ": second channel for node '" + node_name + "' ignored");
      continue;
    }
    animated[static_cast<std::size_t>(node)] = true;
    Channel ch;
    ch.node = node;
    const std::string where = "node '" + node_name + "'";
    // Keys in seconds, strictly increasing: a key at the same time as the one before it is
    // dropped (reported); a key earlier than the one before it refuses the clip.
    auto add_time =
        [&](std::vector<double>& times, double t_ticks, const char* kind, unsigned k) -> bool {
      if (!std::isfinite(t_ticks))
        refuse_clip(where + ", " + kind + " key " + std::to_string(k) + " has a non-finite time");
      const double t = t_ticks / ticks;
      if (!times.empty() && t <= times.back()) {
        if (t < times.back()) {
          refuse_clip(
              where + ", " + kind + " key " + std::to_string(k) + " (t = " + std::to_string(t) +
              " s) is earlier than the key before it (t = " + std::to_string(times.back()) + " s)");
        }
        ctx.problems.push_back(
            label + ", " + where + ": " + kind + " key " + std::to_string(k) +
            " repeats a time; dropped");
        return false;
      }
      times.push_back(t);
      return true;
    };
    if ((na->mNumPositionKeys > 0 && na->mPositionKeys == nullptr) ||
        (na->mNumRotationKeys > 0 && na->mRotationKeys == nullptr) ||
        (na->mNumScalingKeys > 0 && na->mScalingKeys == nullptr)) {
      refuse_clip(where + " lists keys it does not have");
    }
    for (unsigned k = 0; k < na->mNumPositionKeys; ++k) {
      const Eigen::Vector3d v = to_vector(na->mPositionKeys[k].mValue);
      if (!v.allFinite())
        refuse_clip(where + ", translation key " + std::to_string(k) + " is not finite");
      if (add_time(ch.translation_times, na->mPositionKeys[k].mTime, "translation", k))
        ch.translations.push_back(v);
    }
    for (unsigned k = 0; k < na->mNumRotationKeys; ++k) {
      const aiQuaternion& q = na->mRotationKeys[k].mValue;
      Eigen::Quaterniond e(
          static_cast<double>(q.w),
          static_cast<double>(q.x),
          static_cast<double>(q.y),
          static_cast<double>(q.z));
      const double norm = e.norm();
      if (!e.coeffs().allFinite() || !(norm > 0))
        refuse_clip(where + ", rotation key " + std::to_string(k) + " is not a rotation");
      e.coeffs() /= norm;
      if (add_time(ch.rotation_times, na->mRotationKeys[k].mTime, "rotation", k))
        ch.rotations.push_back(e);
    }
    for (unsigned k = 0; k < na->mNumScalingKeys; ++k) {
      const Eigen::Vector3d v = to_vector(na->mScalingKeys[k].mValue);
      if (!v.allFinite())
        refuse_clip(where + ", scale key " + std::to_string(k) + " is not finite");
      if (add_time(ch.scale_times, na->mScalingKeys[k].mTime, "scale", k)) ch.scales.push_back(v);
    }
    for (const auto* times : {&ch.translation_times, &ch.rotation_times, &ch.scale_times}) {
      clip.key_times.insert(clip.key_times.end(), times->begin(), times->end());
    }
    clip.channels.push_back(std::move(ch));
  }
  std::sort(clip.key_times.begin(), clip.key_times.end());
  clip.key_times.erase(
      std::unique(clip.key_times.begin(), clip.key_times.end()), clip.key_times.end());
  // The frame rate: the file's, else the standard rate its keys lie evenly on, else unknown.
  if (ctx.frame_rate_hz > 0) {
    clip.frame_rate_hz = ctx.frame_rate_hz;
    clip.frame_rate_source = FrameRateSource::file;
  } else if (const double grid = key_grid_frame_rate(clip.key_times); grid > 0) {
    clip.frame_rate_hz = grid;
    clip.frame_rate_source = FrameRateSource::key_grid;
  }
  return clip;
}

void read_clips(
    const aiScene* scene,
    const Hierarchy& h,
    Rig& rig,
    std::vector<RefusedClip>& refused,
    Context& ctx) {
  std::vector<bool> hosts_bone(rig.skeleton.nodes.size(), false);
  for (const auto& b : rig.skeleton.bones) hosts_bone[static_cast<std::size_t>(b.node)] = true;
  if (scene->mNumAnimations > 0 && scene->mAnimations == nullptr)
    ctx.invalid("the scene lists animations it does not have");
  std::map<std::string, int> used_names;
  for (unsigned a = 0; a < scene->mNumAnimations; ++a) {
    const aiAnimation* anim = scene->mAnimations[a];
    std::string name = anim != nullptr ? anim->mName.C_Str() : "";
    if (name.empty()) {
      name = "clip_" + std::to_string(a);
      ctx.problems.push_back(
          "animation " + std::to_string(a) + " has no name; called '" + name + "'");
    }
    if (used_names[name]++ > 0) {
      const auto renamed = name + "#" + std::to_string(a);
      ctx.problems.push_back(
          "animation " + std::to_string(a) + " repeats the name '" + name + "'; called '" +
          renamed + "'");
      name = renamed;
    }
    try {
      if (anim == nullptr) refuse_clip("animation " + std::to_string(a) + " is null");
      // Problems found in a clip that is then refused are dropped with it: its refusal says enough.
      const auto problems_before = ctx.problems.size();
      try {
        Clip clip = read_clip(anim, name, h, hosts_bone, rig, ctx);
        if (anim->mNumMorphMeshChannels > 0 || anim->mNumMeshChannels > 0)
          ctx.clips_with_mesh_channels.push_back(name);
        rig.clips.push_back(std::move(clip));
      } catch (const ClipRefusal&) {
        ctx.problems.resize(problems_before);
        throw;
      }
    } catch (const ClipRefusal& refusal) {
      ctx.problems.push_back(
          "clip '" + name + "' refused: " + refusal.reason + "; the other clips are usable");
      refused.push_back({name, refusal.reason});
    }
  }
}

// Non-finite coordinates and weights, before any post-processing step can hide them.
void check_raw_numbers(const aiScene* scene, const Context& ctx) {
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* am = scene->mMeshes[m];
    if (am == nullptr) continue;
    const std::string label = am->mName.length > 0 ? "mesh '" + std::string(am->mName.C_Str()) + "'"
                                                   : "mesh " + std::to_string(m);
    for (unsigned v = 0; am->mVertices != nullptr && v < am->mNumVertices; ++v) {
      if (to_vector(am->mVertices[v]).allFinite()) continue;
      // assimp numbers an OBJ's vertices by face corner, not as the file does: our own reader of
      // OBJ and PLY names the file's vertex (and throws InvalidInput saying so).
      const auto ext = lower(std::filesystem::path(ctx.file).extension().string());
      if (ext == ".obj" || ext == ".ply") (void)read_frame_mesh(ctx.file);
      ctx.invalid(label + ", vertex " + std::to_string(v) + " has a non-finite coordinate");
    }
    for (unsigned b = 0; am->mBones != nullptr && b < am->mNumBones; ++b) {
      const aiBone* bone = am->mBones[b];
      for (unsigned k = 0; bone != nullptr && bone->mWeights != nullptr && k < bone->mNumWeights;
           ++k) {
        if (!std::isfinite(bone->mWeights[k].mWeight)) {
          ctx.invalid(
              label + ", bone '" + std::string(bone->mName.C_Str()) + "' has a non-finite weight");
        }
      }
    }
  }
}

// assimp's JoinIdenticalVertices with the bones set aside, then each bone's weights moved to the
// joined vertices here. assimp 5.2.4 moves them itself with a linear search of a bone's new
// weights for each of its weights — quadratic in a bone's weights: 52 of the 58 ms the step took
// on the 28k-triangle CesiumMan copy (assets/characters/CesiumMan-dense.glb), in the import that
// every check waits for. The same result, linear: a weight goes to the vertex its vertex was
// joined into, of a bone's weights on one joined vertex the first is kept, the weights of a
// vertex in no face are dropped (assimp drops the vertex), and a bone left with none keeps those
// it had (as assimp's step). Which old vertex became which is read off the faces, which the step
// renumbers in place. ImportOptions::assimp_moves_weights runs assimp's own step instead, for
// the test that the two agree (AssimpImport.JoiningMovesTheWeightsAsAssimpDoes).
const aiScene* join_identical_vertices(Assimp::Importer& importer, const aiScene* scene) {
  struct SetAside {
    aiMesh* mesh = nullptr;
    aiBone** bones = nullptr;
    unsigned num_bones = 0;
    unsigned num_vertices = 0;
    std::vector<unsigned> corners;  // every face's vertices, before the step
  };
  std::vector<SetAside> aside;
  // Freed here if the step fails: assimp then frees the scene, which no longer holds them.
  struct Owner {
    std::vector<SetAside>& aside;
    ~Owner() {
      for (SetAside& a : aside) {
        for (unsigned b = 0; b < a.num_bones; ++b) delete a.bones[b];
        delete[] a.bones;
      }
    }
  } owner{aside};
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    aiMesh* mesh = scene->mMeshes[m];
    if (mesh == nullptr || mesh->mNumBones == 0 || mesh->mBones == nullptr) continue;
    SetAside a{
        .mesh = mesh,
        .bones = mesh->mBones,
        .num_bones = mesh->mNumBones,
        .num_vertices = mesh->mNumVertices,
        .corners = {}};
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      a.corners.insert(a.corners.end(), face.mIndices, face.mIndices + face.mNumIndices);
    }
    aside.push_back(std::move(a));
    mesh->mBones = nullptr;
    mesh->mNumBones = 0;
  }
  scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
  if (scene == nullptr) return nullptr;
  constexpr unsigned kNone = std::numeric_limits<unsigned>::max();
  std::vector<unsigned> joined_into;
  std::vector<unsigned> last_bone;  // per joined vertex: the last bone that took a weight of it
  std::vector<aiVertexWeight> moved;
  for (SetAside& a : aside) {
    aiMesh* mesh = a.mesh;
    mesh->mBones = std::exchange(a.bones, nullptr);
    mesh->mNumBones = std::exchange(a.num_bones, 0u);
    joined_into.assign(a.num_vertices, kNone);
    std::size_t k = 0;
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      for (unsigned i = 0; i < face.mNumIndices && k < a.corners.size(); ++i, ++k) {
        // (in range both: ValidateDataStructure checked the read, the step renumbers within)
        if (a.corners[k] < a.num_vertices && face.mIndices[i] < mesh->mNumVertices) {
          joined_into[a.corners[k]] = face.mIndices[i];
        }
      }
    }
    last_bone.assign(mesh->mNumVertices, kNone);
    for (unsigned b = 0; b < mesh->mNumBones; ++b) {
      aiBone* bone = mesh->mBones[b];
      if (bone == nullptr || bone->mWeights == nullptr) continue;
      moved.clear();
      for (unsigned w = 0; w < bone->mNumWeights; ++w) {
        const aiVertexWeight& old = bone->mWeights[w];
        const unsigned into = old.mVertexId < a.num_vertices ? joined_into[old.mVertexId] : kNone;
        if (into == kNone || last_bone[into] == b) continue;
        last_bone[into] = b;
        moved.push_back(aiVertexWeight(into, old.mWeight));
      }
      if (moved.empty()) continue;
      delete[] bone->mWeights;
      bone->mWeights = new aiVertexWeight[moved.size()];
      std::copy(moved.begin(), moved.end(), bone->mWeights);
      bone->mNumWeights = static_cast<unsigned>(moved.size());
    }
  }
  return scene;
}

// The import proper; the caller holds import_mutex().
ImportedRig import_locked(const std::filesystem::path& file, const ImportOptions& options) {
  Context ctx;
  ctx.file = file.string();
  ScopedLogCapture log;
  Assimp::Importer importer;
  // Read and validate first, check the raw data, then post-process: JoinIdenticalVertices
  // compares positions with <, so a NaN vertex would be merged into a neighbour and vanish.
  ScopedStdCapture printed;
  const aiScene* scene = importer.ReadFile(ctx.file, aiProcess_ValidateDataStructure);
  const auto fail_read = [&]() {
    std::string reason = importer.GetErrorString();
    // assimp catches an allocation failure itself and hands back its what() as the reason.
    if (reason.find("bad_alloc") != std::string::npos) throw std::bad_alloc();
    if (reason.empty()) reason = "assimp could not read it";
    throw IoError(ctx.file + ": " + reason);
  };
  if (scene == nullptr) fail_read();
  check_raw_numbers(scene, ctx);
  if (options.join_identical_vertices && options.assimp_moves_weights) {
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  } else {
    scene = importer.ApplyPostProcessing(aiProcess_Triangulate);
    if (scene != nullptr && options.join_identical_vertices) {
      scene = join_identical_vertices(importer, scene);
    }
  }
  for (auto& line : printed.finish()) ctx.problems.push_back("assimp printed: " + line);
  if (scene == nullptr) fail_read();
  // assimp recovers from some broken data by dropping it with a warning; for us that is a
  // wrong answer, not a recovery.
  std::vector<std::string> warnings;
  for (const auto& line : log.lines()) {
    const auto l = lower(line);
    if (l.find("out-of-range") != std::string::npos ||
        l.find("out of range") != std::string::npos) {
      throw InvalidInput(ctx.file + ": " + line);
    }
    if (l.find("bone weight sum") != std::string::npos)
      continue;  // we normalise and report it ourselves
    if (std::find(warnings.begin(), warnings.end(), line) == warnings.end())
      warnings.push_back(line);
  }
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0)
    throw InvalidInput(ctx.file + ": assimp marked the scene incomplete");
  if (scene->mNumMeshes > 0 && scene->mMeshes == nullptr)
    ctx.invalid("the scene lists meshes it does not have");

  ImportedRig out;
  Rig& rig = out.rig;
  rig.source = ctx.file;
  out.unit_scale = options.convert_to_metres ? file_unit_scale(scene, ctx) : 1.0;
  const Eigen::Affine3d unit(Eigen::Scaling(out.unit_scale));
  rig.skeleton.root_transform = unit;

  Hierarchy h = read_hierarchy(scene, rig.skeleton, ctx);
  auto collada = detail::read_collada_extras(file);
  ctx.bind_shapes = std::move(collada.bind_shapes);
  if (!collada.bad_frame_rate.empty() && scene->mNumAnimations > 0) {
    ctx.problems.push_back(
        "Collada <frame_rate> '" + collada.bad_frame_rate + "' is not a positive number; ignored");
  }
  ctx.frame_rate_hz = file_frame_rate(scene, collada.frame_rate_hz, ctx);

  // Meshes in hierarchy order; a mesh instanced by several nodes becomes several parts.
  MeshBuild build;
  for (std::size_t n = 0; n < h.nodes.size(); ++n) {
    const aiNode* node = h.nodes[n];
    if (node == nullptr) continue;  // a static node added for a bone the file lacks
    if (node->mNumMeshes > 0 && node->mMeshes == nullptr)
      ctx.invalid(node_label(node) + " lists meshes it does not have");
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
      const auto mi = node->mMeshes[k];
      if (mi >= scene->mNumMeshes || scene->mMeshes[mi] == nullptr) {
        ctx.invalid(
            node_label(node) + " refers to mesh " + std::to_string(mi) + " out of range [0, " +
            std::to_string(scene->mNumMeshes) + ")");
      }
      add_part(scene, scene->mMeshes[mi], static_cast<std::int32_t>(n), h, unit, rig, build, ctx);
    }
  }
  if (build.triangles.empty()) ctx.invalid("no triangles in the file");
  if (build.positions.size() > static_cast<std::size_t>(INT32_MAX))
    ctx.invalid("too many vertices");

  rig.mesh.rest_positions.resize(static_cast<Eigen::Index>(build.positions.size()), 3);
  for (std::size_t v = 0; v < build.positions.size(); ++v)
    rig.mesh.rest_positions.row(static_cast<Eigen::Index>(v)) = build.positions[v];
  rig.mesh.triangles.resize(static_cast<Eigen::Index>(build.triangles.size()), 3);
  for (std::size_t f = 0; f < build.triangles.size(); ++f) {
    for (int k = 0; k < 3; ++k)
      rig.mesh.triangles(static_cast<Eigen::Index>(f), k) =
          build.triangles[f][static_cast<std::size_t>(k)];
  }
  finish_skin(build, h, rig, ctx);
  out.rest_pose_deviation = build.rest_pose_deviation;
  read_clips(scene, h, rig, out.refused_clips, ctx);

  if (rig.mesh.num_vertices() > 0) {
    const double size = (rig.mesh.rest_positions.colwise().maxCoeff() -
                         rig.mesh.rest_positions.colwise().minCoeff())
                            .norm();
    if (out.rest_pose_deviation > kBindFrameEvidence * size) {
      ctx.problems.push_back(
          "the node hierarchy's rest pose is not the skin's bind pose: skinned vertices move by up "
          "to " +
          std::to_string(out.rest_pose_deviation) + " (" +
          std::to_string(100.0 * out.rest_pose_deviation / size) +
          "% of the model's size) between them");
    }
  }
  if (!ctx.shared_names.empty()) {
    std::string names;
    for (const auto& [name, count] : ctx.shared_names)
      names += (names.empty() ? "'" : ", '") + name + "' (" + std::to_string(count) + ")";
    ctx.problems.push_back(
        "node names shared by several nodes: " + names +
        "; bones and channels bind to the namesake that hosts a bone, else has no mesh, else comes "
        "first");
  }
  if (!ctx.clips_with_mesh_channels.empty()) {
    ctx.problems.push_back(
        std::to_string(ctx.clips_with_mesh_channels.size()) +
        " clips also animate meshes or morph targets; ignored (only node transforms are animated)");
  }
  // assimp's own remarks, after ours: warnings that differ only in their numbers are one line.
  std::vector<std::pair<std::string, std::size_t>> groups;  // (first instance, count)
  std::vector<std::string> patterns;
  for (const auto& w : warnings) {
    std::string pattern;
    for (char c : w) {
      if (std::isdigit(static_cast<unsigned char>(c)) == 0)
        pattern += c;
      else if (pattern.empty() || pattern.back() != '#')
        pattern += '#';
    }
    const auto it = std::find(patterns.begin(), patterns.end(), pattern);
    if (it == patterns.end()) {
      patterns.push_back(pattern);
      groups.emplace_back(w, 1);
    } else {
      ++groups[static_cast<std::size_t>(it - patterns.begin())].second;
    }
  }
  for (std::size_t i = 0; i < groups.size() && i < kMaxForwardedWarnings; ++i) {
    const auto& [first, count] = groups[i];
    ctx.problems.push_back(
        "assimp: " + first + (count > 1 ? " (and " + std::to_string(count - 1) + " similar)" : ""));
  }
  if (groups.size() > kMaxForwardedWarnings) {
    ctx.problems.push_back(
        "assimp: " + std::to_string(groups.size() - kMaxForwardedWarnings) +
        " more kinds of warning");
  }
  validate_rig(rig);
  // One line per distinct remark, in order of first appearance.
  for (auto& p : ctx.problems) {
    if (std::find(out.problems.begin(), out.problems.end(), p) == out.problems.end())
      out.problems.push_back(std::move(p));
  }
  return out;
}

}  // namespace

ImportedRig import_rig(const std::filesystem::path& file, const ImportOptions& options) {
  const std::string name = file.string();
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw IoError(name + ": no such file");
  if (std::filesystem::is_directory(file, ec))
    throw IoError(name + ": is a directory, not a model file");
  if (std::filesystem::file_size(file, ec) == 0 && !ec) throw IoError(name + ": empty file");
  detail::check_declared_counts(file);

  std::unique_lock lock(import_mutex());
  try {
    if (!options.isolate) return import_locked(file, options);
    // A crash, a loop or a runaway allocation inside assimp ends the child, not this process. The
    // child's import is the only one: it sends the rig back, and this process decodes it.
    const detail::ImportLimits limits{
        .memory_bytes = options.memory_limit_bytes,
        .time_s = options.time_limit_s,
        .heap_on_huge_pages = true,
        .while_waiting = options.while_importing};
    detail::ChildAnswer answer =
        detail::run_isolated_with_answer(file, limits, [&](const detail::AnswerSink& send) {
          detail::write_imported_rig(import_locked(file, options), send);
        });
    lock.unlock();  // decoding touches neither assimp nor its logger
    return detail::read_imported_rig(answer, name);
  } catch (const std::bad_alloc&) {
    throw InvalidInput(name + ": ran out of memory importing it");
  }
}

}  // namespace skelcd::skinning
