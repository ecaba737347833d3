#pragma once
// A rigged character: mesh + skeleton (node hierarchy with bones) + skin weights + clips.
// Importers (assimp) and generators fill it; linear blend skinning and RigMotion read it.
// A field added to a struct here must also cross from the import's child process to its parent:
// skinning/detail/imported_rig_stream.cpp, and the comparison in its test.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <cstdint>
#include <string>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::skinning {

/// A node of the transform hierarchy (assimp's aiNode): bones are nodes, and so are the
/// non-bone nodes between them whose animation still moves the bones below.
struct SkeletonNode {
  std::string name;
  std::int32_t parent = -1;  ///< index into Skeleton::nodes; parents precede children
  Eigen::Affine3d rest_local = Eigen::Affine3d::Identity();  ///< static local transform
};

struct Bone {
  std::string name;
  std::int32_t node = -1;    ///< the node that moves this bone
  std::int32_t parent = -1;  ///< nearest ancestor that is a bone, -1 for a root bone
  /// Object space (rest mesh) → bone space at bind time (assimp's offset matrix, with the mesh
  /// node's transform and the unit scale folded in so that rest positions are object space).
  Eigen::Affine3d inverse_bind = Eigen::Affine3d::Identity();
  /// The bone segment at rest, object space: head at the bone's joint, tail at its child's joint
  /// (or extended along the bone when it has no child).
  Eigen::Vector3d rest_head = Eigen::Vector3d::Zero();
  Eigen::Vector3d rest_tail = Eigen::Vector3d::Zero();
};

struct Skeleton {
  std::vector<SkeletonNode> nodes;
  std::vector<Bone> bones;
  /// Applied on top of every node's global transform (the file's unit scale / axis conversion),
  /// so that posed positions are in the same object space as Mesh::rest_positions.
  Eigen::Affine3d root_transform = Eigen::Affine3d::Identity();
  [[nodiscard]] std::int32_t num_bones() const { return static_cast<std::int32_t>(bones.size()); }
};

/// Keyframes of one node: each of translation, rotation, scale is optional and has its own times
/// (seconds). Between keys: lerp (translation, scale) and slerp (rotation); before the first or
/// after the last key the end value holds. A node with no channel keeps its rest_local transform.
struct Channel {
  std::int32_t node = -1;
  std::vector<double> translation_times;
  std::vector<Eigen::Vector3d> translations;
  std::vector<double> rotation_times;
  std::vector<Eigen::Quaterniond> rotations;
  std::vector<double> scale_times;
  std::vector<Eigen::Vector3d> scales;
};

/// Samples per second of a clip whose frame rate is not known (and of the bind pose) (Hz).
inline constexpr double kDefaultSampleRateHz = 30.0;

/// Where a clip's frame rate (Clip::frame_rate_hz) comes from.
enum class FrameRateSource : std::uint8_t {
  none,             ///< not known: the clip is sampled at kDefaultSampleRateHz
  file,             ///< the file declares it (FBX time mode, Collada 3ds Max <frame_rate>)
  key_grid,         ///< the file declares none; its keys are evenly spaced at a standard frame rate
  trajectory_rows,  ///< a robot's joint trajectory: its rows per second
  frame_sequence,   ///< a sequence of mesh frames: one sample per frame (times at 30 Hz)
  generator,        ///< a generated rig: one key per frame
};

/// "default", "file", "key_grid", "trajectory_rows", "frame_sequence", "generator" (for JSON).
[[nodiscard]] const char* to_string(FrameRateSource source);
/// One phrase for people: "the file's frame rate", "default: no frame rate in the file", ….
[[nodiscard]] const char* describe(FrameRateSource source);

/// The standard frame rate (12, 15, 23.976, 24, 25, 29.97, 30, 48, 50, 59.94, 60, 72, 96, 100,
/// 119.88, 120) on which `key_times` (sorted, seconds) lie evenly spaced: at least three keys,
/// every gap within 1 % of the mean gap, and the mean gap's rate within 0.02 % of that
/// standard rate; 0 otherwise. Near-duplicate keys, sparse keys (two keys 1.25 s apart, keys
/// every 0.5 s) and keys on a grid with holes give 0.
[[nodiscard]] double key_grid_frame_rate(const std::vector<double>& key_times);

struct Clip {
  std::string name;
  double duration_s = 0.0;
  std::vector<Channel> channels;
  /// Sorted union of every channel's key times (seconds).
  std::vector<double> key_times;
  /// Frames per second of the clip as made (see FrameRateSource), 0 when not known. The default
  /// sampling rate of a check (sample_rate_hz), not the key rate: keys may be sparser or denser.
  double frame_rate_hz = 0.0;
  FrameRateSource frame_rate_source = FrameRateSource::none;
  /// Samples per second when none is asked for: the frame rate, else kDefaultSampleRateHz.
  [[nodiscard]] double sample_rate_hz() const {
    return frame_rate_hz > 0 ? frame_rate_hz : kDefaultSampleRateHz;
  }
  /// Keys per second: (#key_times - 1) / (last key time - first key time), or 0 when it cannot
  /// be told (fewer than two distinct key times). Measured over the keys' own span, so a clip
  /// whose first key is at 1/24 s still reports 24 keys/s. Informative only: sampling uses
  /// sample_rate_hz (near-duplicate keys would double this rate, sparse keys shrink it).
  [[nodiscard]] double keys_per_s() const {
    if (key_times.size() < 2) return 0.0;
    const double span = key_times.back() - key_times.front();
    return span > 0 ? static_cast<double>(key_times.size() - 1) / span : 0.0;
  }
};

/// #V × #B skin weights, rows normalised to sum 1; a vertex with no influence is rigidly attached
/// to the mesh node's transform (empty row) — see RigMotion.
using SkinWeights = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// How the vertices of one part that carry no skin weight move: rigidly with a node (an unskinned
/// mesh hanging from a node of the hierarchy, as in RobotExpressive.glb).
struct PartAttachment {
  std::int32_t node = -1;  ///< index into Skeleton::nodes; -1: the vertices stay at rest
  /// Object space (rest mesh) → the node's space at rest, like Bone::inverse_bind.
  Eigen::Affine3d inverse_bind = Eigen::Affine3d::Identity();
};

struct Rig {
  Mesh mesh;
  Skeleton skeleton;
  SkinWeights weights;
  std::vector<Clip> clips;
  /// Where it came from (file path or generator spec), for messages and logs.
  std::string source;
  /// #parts or empty. A vertex whose weight row is empty follows the attachment of its part
  /// (Mesh::vertex_part); with no attachment (empty, or node -1) it stays at its rest position.
  std::vector<PartAttachment> part_attachments;

  /// Index of the clip with this name, -1 when there is none.
  [[nodiscard]] std::int32_t find_clip(const std::string& name) const {
    for (std::size_t c = 0; c < clips.size(); ++c) {
      if (clips[c].name == name) return static_cast<std::int32_t>(c);
    }
    return -1;
  }
};

/// Throws InvalidInput naming rig.source when the rig is not usable: mesh invalid, weights shape
/// or sign wrong, node parents not preceding children (cycles), channel nodes out of range,
/// non-finite keys or transforms.
/// Also refused: bone or attachment nodes out of range, a weight row that does not sum to 1
/// (relative 1e-9: rows are normalised at import), key times not increasing, quaternions that are
/// not unit (relative 1e-9), negative durations, a frame rate that is negative or not finite.
void validate_rig(const Rig& rig);

}  // namespace skelcd::skinning
