#pragma once
// What `skelcd info` reports about a model: counts, clips, parts, topology and problems, as one
// JSON object (the human summary is printed from the same object).

#include <nlohmann/json.hpp>

#include "skinning/load.hpp"
#include "skinning/topology.hpp"

namespace skelcd::tools {

/// The report of `model` whose mesh has topology `topology`:
/// {file, kind, triangles, vertices, welded_vertices, edges, bones, nodes,
///  clips: [{name, duration_s, keys_per_s}],
///  parts: [{name, triangles, vertices, closed, components}],
///  components, closed_components, boundary_edges, boundary_loops, non_manifold_edges,
///  degenerate_triangles, unit_scale, rest_pose_deviation, bounding_box: {min, max},
///  problems: [...]} — problems are the loader's, then the topology's.
[[nodiscard]] nlohmann::json model_report(const skinning::LoadedModel& model, const skinning::Topology& topology);

/// The human summary of a model_report, several lines ending in a newline.
[[nodiscard]] std::string format_model_report(const nlohmann::json& report);

}  // namespace skelcd::tools
