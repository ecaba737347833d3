#pragma once
// What `skelcd info` reports about a model: counts, clips, parts, topology and problems, as one
// JSON object (the human summary is printed from the same object).

#include <nlohmann/json.hpp>

#include "skinning/load.hpp"
#include "skinning/topology.hpp"

namespace skelcd::tools {

/// The report of `model` whose mesh has topology `topology`:
/// {file, kind, triangles, vertices, welded_vertices, edges, bones, nodes,
///  clips: [{name, duration_s, keys_per_s, rate_hz, rate_source}] — rate_hz: what a check samples
///    at without --fps, rate_source: where it comes from (skinning::to_string(FrameRateSource):
///    default, file, key_grid, trajectory_rows, frame_sequence, generator),
///  parts: [{name, triangles, vertices, closed, components}],
///  components, closed_components, boundary_edges, boundary_loops, non_manifold_edges,
///  degenerate_triangles, unit_scale, rest_pose_deviation, bounding_box: {min, max},
///  problems: [...]} — problems are the loader's, then the topology's.
[[nodiscard]] nlohmann::json model_report(
    const skinning::LoadedModel& model, const skinning::Topology& topology);

/// The human summary of a model_report, several lines ending in a newline.
[[nodiscard]] std::string format_model_report(const nlohmann::json& report);

}  // namespace skelcd::tools
