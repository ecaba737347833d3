#include "tools/plot.hpp"

#include <plplot.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>

#include "skinning/errors.hpp"

namespace skelcd::tools {
namespace {

// cmap0 indices we redefine: 0 background, 1 axes and text, 2.. one colour per series.
constexpr std::array<std::array<int, 3>, 5> kSeriesColours{{
    {31, 119, 180},   // blue
    {214, 39, 40},    // red
    {44, 160, 44},    // green
    {255, 127, 14},   // orange
    {148, 103, 189},  // purple
}};

constexpr PLINT kGridColour = 15;

/// Range of the series' values, padded so lines do not sit on the frame; [0, 1] when empty.
void bounds(const PlotPanel& panel, double& x_min, double& x_max, double& y_min, double& y_max) {
  x_min = y_min = std::numeric_limits<double>::infinity();
  x_max = y_max = -std::numeric_limits<double>::infinity();
  for (const auto& s : panel.series) {
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x_min = std::min(x_min, s.x[i]);
      x_max = std::max(x_max, s.x[i]);
      y_min = std::min(y_min, s.y[i]);
      y_max = std::max(y_max, s.y[i]);
    }
  }
  if (!std::isfinite(x_min)) x_min = 0, x_max = 1;
  if (!std::isfinite(y_min)) y_min = 0, y_max = 1;
  y_min = std::min(y_min, 0.0);  // counts and times: start the axis at 0
  if (x_max <= x_min) x_max = x_min + 1;
  if (y_max <= y_min) y_max = y_min + 1;
  y_max += 0.08 * (y_max - y_min);
}

void draw_panel(const PlotPanel& panel) {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0;
  bounds(panel, x_min, x_max, y_min, y_max);
  // Frame without a grid, then a light grid, then the axes again on top of it.
  plcol0(1);
  plenv(x_min, x_max, y_min, y_max, 0, -1);
  plcol0(kGridColour);
  plbox("g", 0.0, 0, "g", 0.0, 0);
  plcol0(1);
  plbox("bcnst", 0.0, 0, "bcnstv", 0.0, 0);
  pllab(panel.x_label.c_str(), panel.y_label.c_str(), panel.title.c_str());
  const std::size_t n = std::min(panel.series.size(), kSeriesColours.size());
  std::vector<PLINT> options(n, PL_LEGEND_LINE);
  std::vector<PLINT> colours(n);
  std::vector<PLINT> styles(n, 1);
  std::vector<PLFLT> widths(n, 2.0);
  std::vector<PLINT> text_colours(n, 1);
  std::vector<const char*> labels(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& s = panel.series[i];
    colours[i] = static_cast<PLINT>(2 + i);
    labels[i] = s.label.c_str();
    if (s.x.empty()) continue;
    plcol0(colours[i]);
    plwidth(2.0);
    plline(static_cast<PLINT>(s.x.size()), s.x.data(), s.y.data());
  }
  plwidth(1.0);
  if (n == 0) return;
  PLFLT legend_width = 0;
  PLFLT legend_height = 0;
  pllegend(&legend_width, &legend_height, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_TOP | PL_POSITION_RIGHT | PL_POSITION_INSIDE, 0.01, 0.02, 0.06,
           /*bg_color=*/0, /*bb_color=*/1, /*bb_style=*/1, static_cast<PLINT>(n), 1,
           static_cast<PLINT>(n), options.data(), 1.0, 0.8, 2.0, 0.0, text_colours.data(),
           labels.data(), nullptr, nullptr, nullptr, nullptr, colours.data(), styles.data(),
           widths.data(), nullptr, nullptr, nullptr, nullptr);
}

}  // namespace

void write_png_plot(const std::filesystem::path& path, std::span<const PlotPanel> panels, int width) {
  const std::string name = path.string();
  // PLplot reports a file it cannot open by exiting the process; check writability first.
  {
    std::ofstream probe(path, std::ios::binary | std::ios::trunc);
    if (!probe) throw IoError(name + ": cannot write plot");
  }
  const PLINT rows = std::max<PLINT>(1, static_cast<PLINT>(panels.size()));
  // A stream of our own, so that plotting does not disturb any other PLplot user in the process.
  PLINT stream = 0;
  plmkstrm(&stream);
  if (stream < 0) throw IoError(name + ": PLplot has no free stream");
  plsdev("pngcairo");
  plsfnam(name.c_str());
  plspage(0.0, 0.0, width, 300 * rows, 0, 0);
  plscolbg(255, 255, 255);
  plssub(1, rows);
  plinit();
  plscol0(1, 0, 0, 0);
  plscol0(kGridColour, 220, 220, 220);
  for (std::size_t i = 0; i < kSeriesColours.size(); ++i) {
    const auto& c = kSeriesColours[i];
    plscol0(static_cast<PLINT>(2 + i), c[0], c[1], c[2]);
  }
  plschr(0.0, 1.1);
  for (const auto& panel : panels) draw_panel(panel);
  plend1();
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 || ec) {
    throw IoError(name + ": PLplot wrote no image (is the pngcairo device installed?)");
  }
}

void write_log_plot(const std::filesystem::path& path, const LogData& log, const std::string& title) {
  PlotSeries dcd_pairs{"DCD pairs (per sample)", {}, {}};
  PlotSeries ccd_contacts{"CCD contacts (per interval)", {}, {}};
  PlotSeries dcd_candidates{"DCD rows", {}, {}};
  PlotSeries ccd_candidates{"CCD rows", {}, {}};
  PlotSeries dcd_ms{"DCD rows", {}, {}};
  PlotSeries ccd_ms{"CCD rows", {}, {}};
  for (const auto& row : log.frames) {
    const auto& c = row.counters;
    if (row.kind == QueryKind::dcd) {
      const double x = row.sample;
      dcd_pairs.x.push_back(x);
      dcd_pairs.y.push_back(static_cast<double>(c.dcd_pairs));
      dcd_candidates.x.push_back(x);
      dcd_candidates.y.push_back(static_cast<double>(c.candidate_pairs));
      dcd_ms.x.push_back(x);
      dcd_ms.y.push_back(row.total_us / 1000.0);
    } else {
      const double x = row.sample + 0.5;  // the interval's midpoint
      ccd_contacts.x.push_back(x);
      ccd_contacts.y.push_back(static_cast<double>(c.vf_contacts + c.ee_contacts));
      ccd_candidates.x.push_back(x);
      ccd_candidates.y.push_back(static_cast<double>(c.candidate_pairs));
      ccd_ms.x.push_back(x);
      ccd_ms.y.push_back(row.total_us / 1000.0);
    }
  }
  const auto keep = [](std::vector<PlotSeries> all) {
    std::erase_if(all, [](const PlotSeries& s) { return s.x.empty(); });
    return all;
  };
  const std::vector<PlotPanel> panels{
      {title + " — findings", "sample", "count", keep({dcd_pairs, ccd_contacts})},
      {"candidate triangle pairs", "sample", "pairs", keep({dcd_candidates, ccd_candidates})},
      {"time per frame", "sample", "ms", keep({dcd_ms, ccd_ms})},
  };
  write_png_plot(path, panels);
}

}  // namespace skelcd::tools
