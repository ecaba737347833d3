#pragma once
// One entry point from a MODEL argument to what the commands need: the mesh, the rig when there
// is one, the clips, a factory of Motions, and the problems found on the way.

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "skinning/assimp_import.hpp"
#include "skinning/mesh.hpp"
#include "skinning/mesh_order.hpp"
#include "skinning/motion.hpp"
#include "skinning/rig.hpp"

namespace skelcd::skinning {

/// What a MODEL argument names.
enum class ModelKind {
  rig,             ///< a model file assimp reads (glTF, FBX, Collada, .X, OBJ, PLY, …)
  robot,           ///< a URDF robot (.urdf), moved by a joint trajectory
  frame_sequence,  ///< a folder or a glob of OBJ/PLY frames with one topology
};

[[nodiscard]] const char* to_string(ModelKind kind);

/// An existing regular file is a robot when it ends in `.urdf`, a model file otherwise; a
/// directory, or a path that does not exist and has glob characters (* ? [), is a frame
/// sequence; any other path is classified by its extension (and fails to load later).
[[nodiscard]] ModelKind classify_model_path(const std::filesystem::path& path);

struct LoadOptions {
  /// For model files read by assimp.
  ImportOptions import;
  /// For robots (read by the URDF loader): the joint trajectory CSV (`time,<joint names…>`),
  /// the SRDF whose disabled pairs are excluded, folders searched for `package://` meshes.
  std::filesystem::path trajectory;
  std::filesystem::path srdf;
  std::vector<std::filesystem::path> package_path;
  /// Frame sequences: the order the mesh and its frames are held in (FrameSequenceOptions::order):
  /// spatial unless asked otherwise, as simulators write cloth in no order the checks can read
  /// fast. Model files and robots keep the file's (their writers keep meshes in strips).
  MeshOrder mesh_order = MeshOrder::spatial;
};

/// Name, duration, key rate and default sampling rate of one clip (or trajectory, or frame
/// sequence).
struct ClipSummary {
  std::string name;
  double duration_s = 0.0;
  double keys_per_s = 0.0;  ///< 0 when the clip has fewer than two keys; informative only
  /// Samples per second of a motion that asks for no rate (MotionRequest::rate_hz == 0): the
  /// clip's frame rate (Clip::sample_rate_hz), else kDefaultSampleRateHz.
  double rate_hz = kDefaultSampleRateHz;
  /// Where rate_hz comes from; FrameRateSource::none: the default.
  FrameRateSource rate_source = FrameRateSource::none;
};

/// Which motion to make.
struct MotionRequest {
  /// Clip name; empty picks the first clip (the bind pose when there is none).
  std::string clip;
  /// Samples per second; 0 picks the clip's frame rate (ClipSummary::rate_hz): the file's, the
  /// grid of its evenly spaced keys, a trajectory's rows, else 30 Hz. A frame sequence has one
  /// sample per frame whatever the rate (it only sets their times).
  double rate_hz = 0.0;
};

/// Makes the Motion a request names. @throws InvalidInput for an unknown clip or a bad rate.
using MotionFactory = std::function<std::unique_ptr<Motion>(const MotionRequest&)>;

struct LoadedModel {
  std::filesystem::path path;
  ModelKind kind = ModelKind::rig;
  /// The mesh at rest (never null).
  std::shared_ptr<const Mesh> mesh;
  /// The rig (null for a frame sequence).
  std::shared_ptr<const Rig> rig;
  std::vector<ClipSummary> clips;
  /// Clips of the file that could not be used (see ImportedRig::refused_clips): not in `clips`;
  /// asking for one by name says why it was refused.
  std::vector<RefusedClip> refused_clips;
  /// What was found and handled while loading, one sentence each.
  std::vector<std::string> problems;
  /// Scale applied to the file's coordinates to reach metres (1 when the file has no unit).
  double unit_scale = 1.0;
  /// See ImportedRig::rest_pose_deviation (0 for robots and frame sequences).
  double rest_pose_deviation = 0.0;
  MotionFactory motion_factory;

  /// The motion of `request` (see MotionRequest). @throws InvalidInput naming the file and clip.
  [[nodiscard]] std::unique_ptr<Motion> motion(const MotionRequest& request = {}) const;
};

/// Wraps a rig as a LoadedModel whose motions are RigMotions over its clips. For importers of
/// other kinds of input (URDF robots) that produce a Rig. `refused_clips` are named in errors
/// when a request asks for one of them.
[[nodiscard]] LoadedModel model_from_rig(
    Rig rig,
    ModelKind kind,
    std::vector<std::string> problems,
    std::vector<RefusedClip> refused_clips = {});

/// Loads whatever `path` names (see classify_model_path).
/// @throws IoError / InvalidInput with a message naming the file and the fault.
[[nodiscard]] LoadedModel load_model(const std::filesystem::path& path, const LoadOptions& options = {});

}  // namespace skelcd::skinning
