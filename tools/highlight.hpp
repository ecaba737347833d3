#pragma once
// `skelcd export --highlight LOG.h5`: which triangles of the exported mesh take part in a finding
// of the log at the exported frame, as per-face colours for the exporter.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

#include "skinning/mesh.hpp"
#include "tools/log/log_reader.hpp"

namespace skelcd::tools {

/// Triangles (rows of mesh.triangles, sorted, unique) in a finding keyed to `frame`: both
/// triangles of each DCD pair at sample `frame`; for each CCD contact of the interval
/// [frame, frame + 1], the face and every triangle around the vertex (VF) or along the edges (EE),
/// vertices taken welded (seam duplicates count as one).
/// @throws InvalidInput when the log was not written for this mesh (vertex or triangle count, or a
/// feature id outside it).
[[nodiscard]] std::vector<std::int32_t> highlighted_triangles(
    const LogData& log,
    const skinning::Mesh& mesh,
    std::int32_t frame);

/// How far apart two times of one sample may be and still be the same sample, seconds per second of
/// clip time (at least 1 s counted). Rates derived from single-precision key times differ from
/// round numbers by ~1e-7 relatively (a log written at 23.999999407829137 samples/s puts frame 12
/// at 0.500000012 s, `--rate 24` at 0.5 s); samples of any real rate are more than 1e-3 s apart.
inline constexpr double kSampleTimeTolerance = 1e-6;

/// RGBA in [0, 1] of highlighted and of other triangles.
inline constexpr std::array<float, 4> kHighlightColour{0.9f, 0.1f, 0.1f, 1.0f};
inline constexpr std::array<float, 4> kPlainColour{0.78f, 0.78f, 0.78f, 1.0f};

/// The one call `export --highlight` makes: reads `log_path` and returns #F RGBA face colours,
/// highlighted_triangles() red and the rest grey (ExportOptions::face_colors).
/// @param frame_time_s time of `frame` in the exported motion (seconds): must equal the time the
///   log recorded for that sample, so that a log checked at another rate is not shown on the
///   wrong pose.
/// @param clip name of the exported motion's clip: a (non-scene) log of another clip is refused,
///   so that a model with several clips at one rate is not coloured from the wrong one.
/// @throws IoError / InvalidInput naming the log: unreadable, another mesh, another clip, no row
///   for `frame`, or a different sample time.
[[nodiscard]] std::vector<std::array<float, 4>> highlight_face_colors(
    const std::filesystem::path& log_path,
    const skinning::Mesh& mesh,
    std::int32_t frame,
    double frame_time_s,
    std::string_view clip);

}  // namespace skelcd::tools
