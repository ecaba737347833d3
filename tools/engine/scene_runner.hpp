#pragma once
// Runs a scene (docs/scenes.md): validates and loads what the checks need, plans, then runs every
// check — self checks through ClipRunner, pair checks through culling::PairChecker — writing all
// rows into one HDF5 log with the check of each row. What the command prints: cli/scene_check.hpp.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skinning/load.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/engine/runner.hpp"
#include "tools/engine/scene.hpp"
#include "tools/engine/scene_plan.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

/// True when a MODEL argument names a scene file (ends in `.toml`).
[[nodiscard]] bool is_scene_path(std::string_view model_arg);

struct SceneRunOptions {
  std::filesystem::path log;         ///< empty: no log
  std::optional<FrameRange> frames;  ///< overrides the scene's frames when set
  std::int32_t threads = 1;
  std::string command_line;  ///< for the log header
  /// Called with the plan after validation and before any check runs.
  std::function<void(const ScenePlan&)> on_plan;
  /// Called with an object's name when it is loaded (tests count loads through it).
  std::function<void(std::string_view)> on_load;
  /// Called once every object is loaded and the plan made, with the triangles of the objects the
  /// plan checks, before any check is set up: the checks' runners are built together and hold
  /// their memory together, so this is the size the caller's allocation choices answer to
  /// (`skelcd check`: the heap on huge pages, docs/cli.md "Large allocations").
  std::function<void(std::int64_t triangles)> on_loaded;
  /// Called when a check starts, with its label ("check NAME") and rows; what it returns is called
  /// with the rows done after each row and destroyed when the check ends (the command line draws
  /// its progress line with it). Empty: nothing is shown.
  std::function<std::function<void(std::int64_t)>(const std::string& label, std::int64_t rows)>
      on_check;
};

struct SceneCheckResult {
  std::string name;  ///< CheckPlan::name
  std::vector<FrameRow> rows;
  std::vector<ContactRow> contacts;  ///< parts numbered as in the log (object offsets applied)
  std::vector<DcdPairRow> dcd_pairs;
  RunSummary summary;
  /// A self check's baseline (describe()) and events, ids and parts numbered as in the log;
  /// empty for a pair check (not labelled).
  std::string baseline;
  std::vector<EventRecord> events;
};

struct SceneRunResult {
  ScenePlan plan;
  std::vector<SceneCheckResult> checks;  ///< in plan order
  /// Part names as in the log: "object/part" of every checked object, in object order.
  std::vector<std::string> part_names;
  double total_ms = 0;
};

/// Validates, loads, plans and runs `scene`.
/// @throws InvalidInput "SCENE:LINE: …" before any work and before the log is created for a
///   fault found while loading (a model that does not load, an unknown clip or part, pairs whose
///   objects have different samples, frames outside the samples).
[[nodiscard]] SceneRunResult run_scene(const Scene& scene, const SceneRunOptions& options = {});

/// One object of a scene as its checks see it: its model loaded (a sheet: skinned to its target,
/// which is loaded for it), its clip and rate, its part selection and offset applied.
struct LoadedSceneObject {
  const skinning::LoadedModel* model = nullptr;  ///< the object's model (a sheet's own rig)
  const skinning::Motion* motion = nullptr;      ///< what the object's checks pose
  std::shared_ptr<const void> owner;             ///< keeps model and motion alive
};

/// Loads the object named `name` of `scene` as run_scene does.
/// @throws InvalidInput naming the scene file and line, as run_scene; for an unknown name.
[[nodiscard]] LoadedSceneObject load_scene_object(const Scene& scene, const std::string& name);

}  // namespace skelcd::tools
