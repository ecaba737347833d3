#pragma once
// A scene file (TOML, docs/scenes.md): the objects to move, the checks each needs and the pairs of
// objects to check against each other. Parsing validates everything that can be told from the
// file alone — keys, names, values, that the files it names exist — and refuses the first fault
// with one line naming the scene file and the line of the fault.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "skinning/load.hpp"
#include "tools/engine/events.hpp"
#include "tools/engine/runner.hpp"

namespace skelcd::tools {

/// A generated rectangular sheet (a garment such as a cape): corner + s·u + t·v for s, t in
/// [0, 1], cells_u × cells_v square cells split in two triangles each, in the rest space of the
/// object it is attached to.
struct SceneSheet {
  Eigen::Vector3d corner = Eigen::Vector3d::Zero();
  Eigen::Vector3d u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d v = Eigen::Vector3d::UnitY();
  std::int32_t cells_u = 8;
  std::int32_t cells_v = 8;
};

struct SceneObject {
  std::string name;
  int line = 0;  ///< line of its [objects.NAME] header
  /// The model as load_model takes it: a resolved file or folder path, a glob, or a `gen:` spec.
  /// Empty for a sheet.
  std::string model;
  std::optional<SceneSheet> sheet;
  /// A sheet is skinned with the skeleton of this object: each sheet vertex takes the weights of
  /// the nearest skinned vertex of that object at rest.
  std::string attach_to;
  int attach_line = 0;
  std::string clip;    ///< empty: the model's first clip
  double rate_hz = 0;  ///< 0: the clip's frame rate, else 30 (skinning::ClipSummary::rate_hz)
  /// Trajectory, SRDF and package path of a URDF (resolved).
  skinning::LoadOptions load;
  /// Mesh parts kept (by name); empty: every part.
  std::vector<std::string> parts;
  int parts_line = 0;
  /// Translation applied to every position (model units).
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  bool self_dcd = false;
  bool self_ccd = false;
  int checks_line = 0;
  std::string method;  ///< resolved: the object's own, else the scene's
  int method_line = 0;
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;  ///< resolved likewise
  /// What its self checks' findings are compared with (resolved: its own `baseline`, else the
  /// scene's; a log path resolved against the scene's folder) — docs/events.md.
  BaselineSpec baseline;
  int baseline_line = 0;
  std::int32_t baseline_slack = kDefaultBaselineSlack;
  /// Parts or bones of this object allowed to touch (`allow = ["A:B", …]`) and
  /// `allow_adjacent_bones`.
  Allowances allow;
  int allow_line = 0;

  [[nodiscard]] bool has_self_check() const { return self_dcd || self_ccd; }
};

struct ScenePair {
  std::string a;
  std::string b;
  int line = 0;
  bool dcd = false;
  bool ccd = false;
  ccd::Accuracy accuracy =
      ccd::Accuracy::conservative;  ///< resolved: the pair's own, else the scene's
};

struct Scene {
  std::filesystem::path path;        ///< the scene file, as given
  std::vector<SceneObject> objects;  ///< in file order
  std::vector<ScenePair> pairs;      ///< in file order
  /// The log (resolved against the scene's folder); empty: no log unless the command line names
  /// one.
  std::filesystem::path output;
  std::optional<FrameRange> frames;
  int frames_line = 0;
  double min_separation = 0;
  std::string method = "bvh";
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  BaselineSpec baseline;  ///< the objects' default baseline (`baseline`)

  /// The object named `name`, or null.
  [[nodiscard]] const SceneObject* find(std::string_view name) const;
  /// True when some check (a self check or a pair) names the object.
  [[nodiscard]] bool is_checked(std::string_view name) const;
  /// "FILE:LINE: message" — the one-line form of every scene error.
  [[nodiscard]] std::string where(int line, std::string_view message) const;
};

/// Reads and validates the scene at `path`; relative paths in it resolve against its folder.
/// @throws InvalidInput "SCENE:LINE: …" for a TOML syntax error, an unknown key, check, method or
///   accuracy, a bad value, a pair naming an unknown object, a file that does not exist.
///   IoError when the scene file itself cannot be read.
[[nodiscard]] Scene parse_scene(const std::filesystem::path& path);

/// As parse_scene, from text; `path` names the scene in messages and is the base of relative paths.
[[nodiscard]] Scene parse_scene_text(std::string_view text, const std::filesystem::path& path);

/// The method names a scene accepts: every registered method (culling/method_registry.hpp).
[[nodiscard]] std::vector<std::string> scene_method_names();

}  // namespace skelcd::tools
