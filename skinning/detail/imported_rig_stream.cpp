#include "skinning/detail/imported_rig_stream.hpp"

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "skinning/detail/answer_stream.hpp"
#include "skinning/errors.hpp"

namespace skelcd::skinning::detail {
namespace {

// "SKIR" and a layout version (parent and child are one program, forked: these only catch a
// reader out of step with the writer, or bytes that are not an answer at all).
constexpr std::uint32_t kMagic = 0x52494b53;
constexpr std::uint32_t kVersion = 1;
// Closes the stream: what follows the last field must be exactly this.
constexpr std::uint32_t kEnd = 0x444e4521;

// Arrays of these are sent as one block of doubles.
static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
static_assert(sizeof(Eigen::Quaterniond) == 4 * sizeof(double));
static_assert(sizeof(Eigen::Affine3d) == 16 * sizeof(double));

// Bytes each element takes at least in the stream: a count of N elements must leave N times this
// in the bytes still to read, which bounds every allocation by what was actually received.
constexpr std::size_t kCountBytes = kAnswerCountBytes;
constexpr std::size_t kAffineBytes = 16 * sizeof(double);
constexpr std::size_t kStringMin = kCountBytes;
constexpr std::size_t kNodeMin = kStringMin + sizeof(std::int32_t) + kAffineBytes;
constexpr std::size_t kBoneMin =
    kStringMin + 2 * sizeof(std::int32_t) + kAffineBytes + 6 * sizeof(double);
constexpr std::size_t kChannelMin = sizeof(std::int32_t) + 6 * kCountBytes;
constexpr std::size_t kClipMin =
    kStringMin + sizeof(double) + 2 * kCountBytes + sizeof(double) + sizeof(std::uint8_t);
constexpr std::size_t kAttachmentMin = sizeof(std::int32_t) + kAffineBytes;
constexpr std::size_t kRefusedClipMin = 2 * kStringMin;

// The rig's transforms and points go as blocks of doubles.
class Writer : public AnswerWriter {
 public:
  using AnswerWriter::AnswerWriter;
  void affine(const Eigen::Affine3d& t) { block(t.matrix().data(), kAffineBytes); }
  void vector3(const Eigen::Vector3d& v) { block(v.data(), sizeof v); }
};

class Reader : public AnswerReader {
 public:
  Reader(ChildAnswer& in, const std::string& file) : AnswerReader(in, file, "the import's") {}
  Eigen::Affine3d affine() {
    Eigen::Affine3d t;
    bytes(t.matrix().data(), kAffineBytes);
    return t;
  }
  Eigen::Vector3d vector3() {
    Eigen::Vector3d v;
    bytes(v.data(), sizeof v);
    return v;
  }
};

// --- writing, field by field in the order of the structs (skinning/rig.hpp, mesh.hpp) ---------

void write_mesh(Writer& w, const Mesh& mesh) {
  w.count(static_cast<std::size_t>(mesh.rest_positions.rows()));
  w.block(
      mesh.rest_positions.data(),
      static_cast<std::size_t>(mesh.rest_positions.size()) * sizeof(double));
  w.count(static_cast<std::size_t>(mesh.triangles.rows()));
  w.block(
      mesh.triangles.data(),
      static_cast<std::size_t>(mesh.triangles.size()) * sizeof(std::int32_t));
  w.array(mesh.face_part);
  w.array(mesh.face_index_in_part);
  w.array(mesh.vertex_part);
  w.array(mesh.vertex_index_in_part);
  w.strings(mesh.part_names);
  w.count(mesh.excluded_part_pairs.size());
  for (const auto& [a, b] : mesh.excluded_part_pairs) {
    w.scalar(a);
    w.scalar(b);
  }
}

void write_skeleton(Writer& w, const Skeleton& skeleton) {
  w.count(skeleton.nodes.size());
  for (const auto& node : skeleton.nodes) {
    w.string(node.name);
    w.scalar(node.parent);
    w.affine(node.rest_local);
  }
  w.count(skeleton.bones.size());
  for (const auto& bone : skeleton.bones) {
    w.string(bone.name);
    w.scalar(bone.node);
    w.scalar(bone.parent);
    w.affine(bone.inverse_bind);
    w.vector3(bone.rest_head);
    w.vector3(bone.rest_tail);
  }
  w.affine(skeleton.root_transform);
}

// Rows, columns, then the compressed row-major arrays: #rows + 1 row starts, #nonzeros column
// indices and values.
void write_weights(Writer& w, const SkinWeights& weights) {
  SkinWeights compressed;
  const SkinWeights* W = &weights;
  if (!weights.isCompressed()) {  // the importer compresses; a copy only if it ever stops
    compressed = weights;
    compressed.makeCompressed();
    W = &compressed;
  }
  w.count(static_cast<std::size_t>(W->rows()));
  w.count(static_cast<std::size_t>(W->cols()));
  w.count(static_cast<std::size_t>(W->nonZeros()));
  using Index = SkinWeights::StorageIndex;
  w.block(W->outerIndexPtr(), static_cast<std::size_t>(W->rows() + 1) * sizeof(Index));
  w.block(W->innerIndexPtr(), static_cast<std::size_t>(W->nonZeros()) * sizeof(Index));
  w.block(W->valuePtr(), static_cast<std::size_t>(W->nonZeros()) * sizeof(double));
}

void write_clip(Writer& w, const Clip& clip) {
  w.string(clip.name);
  w.scalar(clip.duration_s);
  w.count(clip.channels.size());
  for (const auto& c : clip.channels) {
    w.scalar(c.node);
    w.array(c.translation_times);
    w.array(c.translations);
    w.array(c.rotation_times);
    w.array(c.rotations);
    w.array(c.scale_times);
    w.array(c.scales);
  }
  w.array(clip.key_times);
  w.scalar(clip.frame_rate_hz);
  w.scalar(static_cast<std::uint8_t>(clip.frame_rate_source));
}

// --- reading, the same order; counts bounded by the bytes left ------------------------------

Mesh read_mesh(Reader& r) {
  Mesh mesh;
  const auto vertices = r.count(3 * sizeof(double), "vertices");
  mesh.rest_positions.resize(static_cast<Eigen::Index>(vertices), 3);
  r.bytes(mesh.rest_positions.data(), vertices * 3 * sizeof(double));
  const auto triangles = r.count(3 * sizeof(std::int32_t), "triangles");
  mesh.triangles.resize(static_cast<Eigen::Index>(triangles), 3);
  r.bytes(mesh.triangles.data(), triangles * 3 * sizeof(std::int32_t));
  mesh.face_part = r.array<std::int32_t>("face parts");
  mesh.face_index_in_part = r.array<std::int32_t>("face indices");
  mesh.vertex_part = r.array<std::int32_t>("vertex parts");
  mesh.vertex_index_in_part = r.array<std::int32_t>("vertex indices");
  mesh.part_names = r.strings("part names");
  mesh.excluded_part_pairs.resize(r.count(2 * sizeof(std::int32_t), "excluded part pairs"));
  for (auto& [a, b] : mesh.excluded_part_pairs) {
    a = r.scalar<std::int32_t>();
    b = r.scalar<std::int32_t>();
  }
  return mesh;
}

Skeleton read_skeleton(Reader& r) {
  Skeleton skeleton;
  skeleton.nodes.resize(r.count(kNodeMin, "nodes"));
  for (auto& node : skeleton.nodes) {
    node.name = r.string("node name bytes");
    node.parent = r.scalar<std::int32_t>();
    node.rest_local = r.affine();
  }
  skeleton.bones.resize(r.count(kBoneMin, "bones"));
  for (auto& bone : skeleton.bones) {
    bone.name = r.string("bone name bytes");
    bone.node = r.scalar<std::int32_t>();
    bone.parent = r.scalar<std::int32_t>();
    bone.inverse_bind = r.affine();
    bone.rest_head = r.vector3();
    bone.rest_tail = r.vector3();
  }
  skeleton.root_transform = r.affine();
  return skeleton;
}

SkinWeights read_weights(Reader& r) {
  using Index = SkinWeights::StorageIndex;
  constexpr auto kIndexMax = static_cast<std::size_t>(std::numeric_limits<Index>::max());
  const auto rows = r.count(sizeof(Index), "weight rows");
  const auto cols = r.scalar<std::uint64_t>();
  const auto nonzeros = r.count(sizeof(Index) + sizeof(double), "weights");
  if (rows >= kIndexMax || cols > kIndexMax || nonzeros > kIndexMax)
    r.damaged("a weight matrix of more than 2^31 rows, columns or entries");
  if (r.left() < (rows + 1) * sizeof(Index) + nonzeros * (sizeof(Index) + sizeof(double)))
    r.damaged("the weights end early");
  SkinWeights W(static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  W.resizeNonZeros(static_cast<Eigen::Index>(nonzeros));
  r.bytes(W.outerIndexPtr(), (rows + 1) * sizeof(Index));
  r.bytes(W.innerIndexPtr(), nonzeros * sizeof(Index));
  r.bytes(W.valuePtr(), nonzeros * sizeof(double));
  // Eigen trusts this layout: row starts from 0 to #nonzeros, never decreasing; within a row,
  // columns in range and increasing. Every start is checked before any is used as an index: a
  // start beyond #nonzeros followed by a smaller one would otherwise be read through first.
  const Index* start = W.outerIndexPtr();
  const Index* column = W.innerIndexPtr();
  if (start[0] != 0 || static_cast<std::size_t>(start[rows]) != nonzeros)
    r.damaged("the weights' row starts do not span their entries");
  for (std::size_t v = 0; v < rows; ++v) {
    if (start[v + 1] < start[v])
      r.damaged("weight row " + std::to_string(v) + " ends before it starts");
  }
  for (std::size_t v = 0; v < rows; ++v) {
    for (Index k = start[v]; k < start[v + 1]; ++k) {
      if (column[k] < 0 || static_cast<std::uint64_t>(column[k]) >= cols ||
          (k > start[v] && column[k] <= column[k - 1]))
        r.damaged(
            "weight row " + std::to_string(v) + " has its bone columns out of order or range");
    }
  }
  return W;
}

Clip read_clip(Reader& r) {
  Clip clip;
  clip.name = r.string("clip name bytes");
  clip.duration_s = r.scalar<double>();
  clip.channels.resize(r.count(kChannelMin, "channels"));
  for (auto& c : clip.channels) {
    c.node = r.scalar<std::int32_t>();
    c.translation_times = r.array<double>("translation key times");
    c.translations = r.array<Eigen::Vector3d>("translation keys");
    c.rotation_times = r.array<double>("rotation key times");
    c.rotations = r.array<Eigen::Quaterniond>("rotation keys");
    c.scale_times = r.array<double>("scale key times");
    c.scales = r.array<Eigen::Vector3d>("scale keys");
  }
  clip.key_times = r.array<double>("clip key times");
  clip.frame_rate_hz = r.scalar<double>();
  const auto source = r.scalar<std::uint8_t>();
  if (source > static_cast<std::uint8_t>(FrameRateSource::generator))
    r.damaged("frame rate source " + std::to_string(source) + " is not one");
  clip.frame_rate_source = static_cast<FrameRateSource>(source);
  return clip;
}

// What validate_rig takes for granted rather than checks: per-face and per-vertex arrays as long
// as the mesh, weights with a row per vertex.
void check_shapes(Reader& r, const Rig& rig) {
  const auto V = static_cast<std::size_t>(rig.mesh.num_vertices());
  const auto F = static_cast<std::size_t>(rig.mesh.num_triangles());
  const Mesh& m = rig.mesh;
  if (m.face_part.size() != F || m.face_index_in_part.size() != F || m.vertex_part.size() != V ||
      m.vertex_index_in_part.size() != V)
    r.damaged("per-face or per-vertex arrays of the wrong length");
  if (rig.weights.size() > 0 && static_cast<std::size_t>(rig.weights.rows()) != V)
    r.damaged("a weight matrix whose rows are not the vertices");
}

}  // namespace

void write_imported_rig(const ImportedRig& imported, const AnswerSink& send) {
  Writer w(send);
  w.scalar(kMagic);
  w.scalar(kVersion);
  const Rig& rig = imported.rig;
  write_mesh(w, rig.mesh);
  write_skeleton(w, rig.skeleton);
  write_weights(w, rig.weights);
  w.count(rig.clips.size());
  for (const auto& clip : rig.clips) write_clip(w, clip);
  w.string(rig.source);
  w.count(rig.part_attachments.size());
  for (const auto& a : rig.part_attachments) {
    w.scalar(a.node);
    w.affine(a.inverse_bind);
  }
  w.count(imported.refused_clips.size());
  for (const auto& refused : imported.refused_clips) {
    w.string(refused.name);
    w.string(refused.reason);
  }
  w.strings(imported.problems);
  w.scalar(imported.unit_scale);
  w.scalar(imported.rest_pose_deviation);
  w.scalar(kEnd);
}

ImportedRig read_imported_rig(ChildAnswer& bytes, const std::string& file) {
  Reader r(bytes, file);
  if (r.scalar<std::uint32_t>() != kMagic || r.scalar<std::uint32_t>() != kVersion)
    r.damaged("it does not start as an imported rig");
  ImportedRig out;
  Rig& rig = out.rig;
  rig.mesh = read_mesh(r);
  rig.skeleton = read_skeleton(r);
  rig.weights = read_weights(r);
  rig.clips.resize(r.count(kClipMin, "clips"));
  for (auto& clip : rig.clips) clip = read_clip(r);
  rig.source = r.string("source bytes");
  rig.part_attachments.resize(r.count(kAttachmentMin, "part attachments"));
  for (auto& a : rig.part_attachments) {
    a.node = r.scalar<std::int32_t>();
    a.inverse_bind = r.affine();
  }
  out.refused_clips.resize(r.count(kRefusedClipMin, "refused clips"));
  for (auto& refused : out.refused_clips) {
    refused.name = r.string("refused clip name bytes");
    refused.reason = r.string("refusal bytes");
  }
  out.problems = r.strings("problems");
  out.unit_scale = r.scalar<double>();
  out.rest_pose_deviation = r.scalar<double>();
  if (r.scalar<std::uint32_t>() != kEnd) r.damaged("its fields do not end where the rig does");
  if (r.left() != 0) r.damaged(std::to_string(r.left()) + " bytes after the rig");
  check_shapes(r, rig);
  // The child validated the rig it sent; the same check here turns a stream that was damaged in
  // a way the layout cannot tell (an index out of range) into this error, not a crash later.
  try {
    validate_rig(rig);
  } catch (const InvalidInput& e) {
    r.damaged(e.what());
  }
  return out;
}

}  // namespace skelcd::skinning::detail
