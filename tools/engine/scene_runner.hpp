#pragma once
// Runs a scene (docs/scenes.md): validates and loads what the checks need, plans, prints the plan,
// then runs every check — self checks through ClipRunner, pair checks through
// culling::PairChecker — writing all rows into one HDF5 log with the check of each row.

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

/// What `skelcd check SCENE.toml` passes on from its command line.
struct SceneCheckArguments {
  std::string output;  ///< -o: the log (overrides the scene's `output`); empty: the scene's
  std::string frames;  ///< --frames A:B (overrides the scene's `frames`); empty: the scene's
  std::int32_t threads =
      1;  ///< self checks: worker threads (0: all cores); pair checks run serially
  bool json = false;
};

/// True when a MODEL argument names a scene file (ends in `.toml`).
[[nodiscard]] bool is_scene_path(std::string_view model_arg);

/// `skelcd check SCENE.toml`: prints the plan, runs, prints a summary per check (or one JSON
/// object with the plan and the summaries), writes the log.
/// @throws InvalidInput "SCENE:LINE: …" for anything refused before work starts (nothing is
///   written then); IoError when the log cannot be written.
void run_scene_check(const std::filesystem::path& scene, const SceneCheckArguments& args);

struct SceneRunOptions {
  std::filesystem::path log;         ///< empty: no log
  std::optional<FrameRange> frames;  ///< overrides the scene's frames when set
  std::int32_t threads = 1;
  std::string command_line;  ///< for the log header
  /// Called with the plan after validation and before any check runs.
  std::function<void(const ScenePlan&)> on_plan;
  /// Called with an object's name when it is loaded (tests count loads through it).
  std::function<void(std::string_view)> on_load;
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
