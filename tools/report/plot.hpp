#pragma once
// PNG plots with PLplot (pngcairo device): a page of panels stacked vertically, each of lines or of
// bars on lanes (a timeline); the per-log page `skelcd inspect --plot` writes (findings, candidate
// pairs and time per frame, the events) and its timeline of the events of many logs.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tools/io/log/log_reader.hpp"

namespace skelcd::tools {

struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;  ///< same length as x
};

/// A bar on a lane, from x0 to x1 (a point when equal: drawn a little wide), coloured by `colour`
/// (an event id: a distinct colour each, cycling through a palette of 12), labelled `text`.
struct PlotBar {
  double x0 = 0;
  double x1 = 0;
  std::int32_t colour = 0;
  std::string text;
};

/// One lane of a timeline panel: bars that overlap stack within the lane.
struct PlotLane {
  std::string label;  ///< drawn left of the lane (a clip's name); "" for none
  std::vector<PlotBar> bars;
  /// A thin grey line from span_begin to span_end under the bars (what was checked); none when
  /// span_end < span_begin.
  double span_begin = 0;
  double span_end = -1;
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
  /// When not empty, the panel is a timeline of these lanes (top to bottom) instead of lines.
  std::vector<PlotLane> lanes;
  /// The x range of a timeline (to line it up with the panels above); from the bars when
  /// x_max <= x_min.
  double x_min = 0;
  double x_max = 0;
};

/// Writes `panels` one above the other into the PNG `path` (width × 300 px per panel).
/// @throws IoError naming `path` when the PNG cannot be written.
void write_png_plot(
    const std::filesystem::path& path,
    std::span<const PlotPanel> panels,
    int width = 1000,
    int panel_height = 300);

/// The per-log page: findings per frame (DCD pairs, CCD contacts; new ones too in a labelled log),
/// candidate triangle pairs per frame, and ms per frame (DCD and CCD rows), against the sample
/// index; below them, when the log has events, each event from its first to its last sample.
void write_log_plot(
    const std::filesystem::path& path, const LogData& log, const std::string& title);

/// One timeline: a lane per entry of `lanes` (a clip), its events as bars over time (seconds).
/// 1000 px wide, 300 px or 40 px per lane.
void write_events_timeline(
    const std::filesystem::path& path,
    const std::vector<PlotLane>& lanes,
    const std::string& title);

}  // namespace skelcd::tools
