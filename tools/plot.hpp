#pragma once
// PNG line plots with PLplot (pngcairo device): a page of panels stacked vertically, and the
// per-log page `skelcd inspect --plot` writes (findings, candidate pairs and time per frame).

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "tools/log/log_reader.hpp"

namespace skelcd::tools {

struct PlotSeries {
  std::string label;
  std::vector<double> x;
  std::vector<double> y;  ///< same length as x
};

struct PlotPanel {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<PlotSeries> series;
};

/// Writes `panels` one above the other into the PNG `path` (width × 300 px per panel).
/// @throws IoError naming `path` when the PNG cannot be written.
void write_png_plot(
    const std::filesystem::path& path,
    std::span<const PlotPanel> panels,
    int width = 1000);

/// The per-log page: findings per frame (DCD pairs, CCD contacts), candidate triangle pairs per
/// frame, and ms per frame (DCD and CCD rows), against the sample index.
void write_log_plot(const std::filesystem::path& path, const LogData& log, const std::string& title);

}  // namespace skelcd::tools
