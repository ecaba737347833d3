#pragma once
// A scene's plan for people and programs: the text `skelcd check SCENE.toml` prints first and the
// `plan` object of its --json (docs/scenes.md, "The plan").

#include <nlohmann/json.hpp>
#include <ostream>

#include "tools/engine/scene_plan.hpp"

namespace skelcd::tools {

/// The plan as text (a few lines per object and check).
void print_plan(std::ostream& out, const ScenePlan& plan);

/// The plan as JSON: {"scene", "objects": [{name, checked, stages: {…}, skipped: […], …}],
/// "checks": […]}.
[[nodiscard]] nlohmann::json plan_json(const ScenePlan& plan);

}  // namespace skelcd::tools
