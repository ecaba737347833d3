#pragma once
// `skelcd export --highlight LOG.h5`: which triangles of the exported mesh take part in a finding
// of the log at the exported frame, as per-face colours for the exporter: a colour per collision
// event, and neutral ones for what the baseline had and what was allowed (docs/events.md).

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "skinning/mesh.hpp"
#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {

/// Triangles (rows of mesh.triangles, sorted, unique) in a finding keyed to `frame`: both
/// triangles of each DCD pair at sample `frame`; for each CCD contact of the interval
/// [frame, frame + 1], the face and every triangle around the vertex (VF) or along the edges (EE),
/// vertices taken welded (seam duplicates count as one).
/// @throws InvalidInput when the log was not written for this mesh (vertex or triangle count, or a
/// feature id outside it).
[[nodiscard]] std::vector<std::int32_t> highlighted_triangles(
    const LogData& log, const skinning::Mesh& mesh, std::int32_t frame);

/// The same triangles, each with the label of its finding (frame_report.hpp: an event id,
/// kLabelBaseline, kLabelAllowed, kLabelNone), sorted by triangle. A triangle in several findings
/// takes the first of: the smallest event id, baseline, allowed, unlabelled.
/// @throws InvalidInput as highlighted_triangles().
[[nodiscard]] std::vector<std::pair<std::int32_t, std::int32_t>> labelled_triangles(
    const LogData& log, const skinning::Mesh& mesh, std::int32_t frame);

/// How far apart two times of one sample may be and still be the same sample, seconds per second of
/// clip time (at least 1 s counted). Rates derived from single-precision key times differ from
/// round numbers by ~1e-7 relatively (a log written at 23.999999407829137 samples/s puts frame 12
/// at 0.500000012 s, `--rate 24` at 0.5 s); samples of any real rate are more than 1e-3 s apart.
inline constexpr double kSampleTimeTolerance = 1e-6;

/// RGBA in [0, 1] of highlighted (a log without labels) and of other triangles.
inline constexpr std::array<float, 4> kHighlightColour{0.9f, 0.1f, 0.1f, 1.0f};
inline constexpr std::array<float, 4> kPlainColour{0.78f, 0.78f, 0.78f, 1.0f};
/// Neutral colours of a labelled log's findings that are not new: the baseline's (slate) and
/// allowed ones (khaki).
inline constexpr std::array<float, 4> kBaselineColour{0.35f, 0.40f, 0.50f, 1.0f};
inline constexpr std::array<float, 4> kAllowedColour{0.62f, 0.57f, 0.40f, 1.0f};

/// One colour per event id, cycling (id % 12): the same in `export --highlight` and in the event
/// bars of `inspect --plot`. None is grey, slate or khaki.
struct PaletteColour {
  unsigned char r, g, b;
  const char* name;
};
inline constexpr std::array<PaletteColour, 12> kEventPalette{{
    {228, 26, 28, "red"},
    {55, 126, 184, "blue"},
    {77, 175, 74, "green"},
    {152, 78, 163, "purple"},
    {255, 127, 0, "orange"},
    {166, 86, 40, "brown"},
    {247, 129, 191, "pink"},
    {23, 190, 207, "cyan"},
    {188, 189, 34, "olive"},
    {31, 60, 120, "navy"},
    {255, 217, 47, "yellow"},
    {102, 194, 165, "teal"},
}};
[[nodiscard]] const PaletteColour& event_palette(std::int32_t event);
/// RGBA in [0, 1] of a label: its event's palette colour, kBaselineColour, kAllowedColour, or
/// kHighlightColour for an unlabelled finding.
[[nodiscard]] std::array<float, 4> label_colour(std::int32_t label);

/// What export --highlight colours: #F RGBA face colours, and the triangles per label at the frame
/// (its legend).
struct Highlight {
  std::vector<std::array<float, 4>> face_colors;
  std::map<std::int32_t, std::int64_t> triangles_per_label;
  bool labelled = false;  ///< the log labels its findings (header.baseline not empty)
};

/// "event 0 red: 12 triangles, event 3 cyan: 4, baseline (slate): 20, allowed (khaki): 2", or
/// "12 triangles in red" for an unlabelled log, "no finding at this frame".
[[nodiscard]] std::string legend(const Highlight& highlight);

/// The one call `export --highlight` makes: reads `log_path` and colours labelled_triangles() by
/// label_colour() and the rest kPlainColour (Highlight::face_colors → ExportOptions::face_colors).
/// A log without labels (written before events) keeps one colour, kHighlightColour.
/// @param frame_time_s time of `frame` in the exported motion (seconds): must equal the time the
///   log recorded for that sample, so that a log checked at another rate is not shown on the
///   wrong pose.
/// @param clip name of the exported motion's clip: a (non-scene) log of another clip is refused,
///   so that a model with several clips at one rate is not coloured from the wrong one.
/// @throws IoError / InvalidInput naming the log: unreadable, another mesh, another clip, no row
///   for `frame`, or a different sample time.
[[nodiscard]] Highlight highlight_frame(
    const std::filesystem::path& log_path,
    const skinning::Mesh& mesh,
    std::int32_t frame,
    double frame_time_s,
    std::string_view clip);

/// highlight_frame(…).face_colors.
[[nodiscard]] std::vector<std::array<float, 4>> highlight_face_colors(
    const std::filesystem::path& log_path,
    const skinning::Mesh& mesh,
    std::int32_t frame,
    double frame_time_s,
    std::string_view clip);

}  // namespace skelcd::tools
