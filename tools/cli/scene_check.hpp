#pragma once
// `skelcd check SCENE.toml` (docs/scenes.md): runs a scene through engine/scene_runner.hpp and
// prints its plan, a progress line per check and its results (text, or one JSON object).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace skelcd::tools {

/// What `skelcd check SCENE.toml` passes on from its command line.
struct SceneCheckArguments {
  std::string output;  ///< -o: the log (overrides the scene's `output`); empty: the scene's
  std::string frames;  ///< --frames A:B (overrides the scene's `frames`); empty: the scene's
  std::int32_t threads =
      1;  ///< self checks: worker threads (0: all cores); pair checks run serially
  bool json = false;
  /// Called once the scene's objects are loaded, with the triangles of those it checks, before
  /// any check is set up (`check`'s hook: the heap on huge pages for a large scene, as for a large
  /// model; commands.hpp, on_check_model_loaded). Empty: nothing.
  std::function<void(std::int64_t triangles)> on_loaded;
};

/// `skelcd check SCENE.toml`: prints the plan, runs, prints a summary per check (or one JSON
/// object with the plan and the summaries), writes the log.
/// @throws InvalidInput "SCENE:LINE: …" for anything refused before work starts (nothing is
///   written then); IoError when the log cannot be written.
void run_scene_check(const std::filesystem::path& scene, const SceneCheckArguments& args);

}  // namespace skelcd::tools
