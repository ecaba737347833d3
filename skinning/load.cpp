#include "skinning/load.hpp"

#include <algorithm>
#include <cctype>
#include <string>
#include <utility>

#include "skinning/errors.hpp"
#include "skinning/frame_sequence.hpp"
#include "skinning/generators.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/urdf.hpp"

namespace skelcd::skinning {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string clip_list(const std::vector<ClipSummary>& clips) {
  if (clips.empty()) return "it has none";
  std::string list = "clips:";
  for (const auto& c : clips) list += " '" + c.name + "'";
  return list;
}

LoadedModel load_assimp_model(const std::filesystem::path& path, const LoadOptions& options) {
  if (!options.trajectory.empty() || !options.srdf.empty() || !options.package_path.empty()) {
    throw InvalidInput(path.string() + ": a trajectory, SRDF or package path applies to URDF robots only");
  }
  auto imported = import_rig(path, options.import);
  auto model = model_from_rig(
      std::move(imported.rig),
      ModelKind::rig,
      std::move(imported.problems),
      std::move(imported.refused_clips));
  model.path = path;
  model.unit_scale = imported.unit_scale;
  model.rest_pose_deviation = imported.rest_pose_deviation;
  return model;
}

}  // namespace

const char* to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::rig:
      return "rig";
    case ModelKind::robot:
      return "robot";
    case ModelKind::frame_sequence:
      return "frame sequence";
  }
  return "?";
}

ModelKind classify_model_path(const std::filesystem::path& path) {
  std::error_code ec;
  const bool is_urdf = lower(path.extension().string()) == ".urdf";
  // An existing file is a file, even when its name has glob characters ("walk[2].glb").
  if (std::filesystem::is_regular_file(path, ec)) return is_urdf ? ModelKind::robot : ModelKind::rig;
  if (std::filesystem::is_directory(path, ec)) return ModelKind::frame_sequence;
  if (path.string().find_first_of("*?[") != std::string::npos) return ModelKind::frame_sequence;
  return is_urdf ? ModelKind::robot : ModelKind::rig;
}

std::unique_ptr<Motion> LoadedModel::motion(const MotionRequest& request) const {
  if (!motion_factory) throw InvalidInput(path.string() + ": this model cannot move");
  return motion_factory(request);
}

LoadedModel model_from_rig(
    Rig rig,
    ModelKind kind,
    std::vector<std::string> problems,
    std::vector<RefusedClip> refused_clips) {
  LoadedModel model;
  model.path = rig.source;
  model.kind = kind;
  auto shared = std::make_shared<const Rig>(std::move(rig));
  model.rig = shared;
  model.mesh = std::shared_ptr<const Mesh>(shared, &shared->mesh);  // shares the rig's lifetime
  for (const auto& c : shared->clips) {
    const auto source = c.frame_rate_hz > 0 ? c.frame_rate_source : FrameRateSource::none;
    model.clips.push_back({c.name, c.duration_s, c.keys_per_s(), c.sample_rate_hz(), source});
  }
  model.problems = std::move(problems);
  model.refused_clips = std::move(refused_clips);
  model.motion_factory = [shared, clips = model.clips, refused = model.refused_clips](
                             const MotionRequest& request) -> std::unique_ptr<Motion> {
    RigMotionOptions options;
    options.rate_hz = request.rate_hz;
    if (!request.clip.empty()) {
      options.clip = shared->find_clip(request.clip);
      const auto refusal = std::find_if(refused.begin(), refused.end(), [&](const RefusedClip& r) {
        return r.name == request.clip;
      });
      if (options.clip < 0 && refusal != refused.end()) {
        throw InvalidInput(
            shared->source + ": clip '" + request.clip + "' was refused: " + refusal->reason +
            " (" +
            (clips.empty() ? std::string("no clip is usable") : "usable " + clip_list(clips)) +
            ")");
      }
      if (options.clip < 0) {
        throw InvalidInput(shared->source + ": no clip named '" + request.clip + "' (" + clip_list(clips) + ")");
      }
    } else {
      options.clip = shared->clips.empty() ? -1 : 0;
    }
    return std::make_unique<RigMotion>(shared, options);
  };
  return model;
}

LoadedModel load_model(const std::filesystem::path& path, const LoadOptions& options) {
  // `gen:NAME?…` names a generated rig (skinning/generators.hpp), not a file.
  if (is_generator_spec(path.string())) return load_generated_model(path.string(), options);
  switch (classify_model_path(path)) {
    // One loader per kind; each returns a complete LoadedModel (model_from_rig() wraps a Rig).
    case ModelKind::frame_sequence:
      return load_frame_sequence_model(path, options);  // skinning/frame_sequence.hpp
    case ModelKind::robot:
      return load_urdf_model(path, options);  // skinning/urdf.hpp (+ urdf_model.cpp)
    case ModelKind::rig:
      break;
  }
  return load_assimp_model(path, options);
}

}  // namespace skelcd::skinning
