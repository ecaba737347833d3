#include "tools/report/plot.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>

#include "skinning/errors.hpp"
#include "tools/report/highlight.hpp"
#include "tools/report/plplot_library.hpp"

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
constexpr PLINT kSpanColour = 14;

// cmap0 indices 16.. : one colour per event id (kEventPalette, as export --highlight colours them).
constexpr PLINT kEventColourBase = 16;
constexpr auto kEventColours = static_cast<PLINT>(kEventPalette.size());

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
  pllegend(
      &legend_width,
      &legend_height,
      PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
      PL_POSITION_TOP | PL_POSITION_RIGHT | PL_POSITION_INSIDE,
      0.01,
      0.02,
      0.06,
      /*bg_color=*/0,
      /*bb_color=*/1,
      /*bb_style=*/1,
      static_cast<PLINT>(n),
      1,
      static_cast<PLINT>(n),
      options.data(),
      1.0,
      0.8,
      2.0,
      0.0,
      text_colours.data(),
      labels.data(),
      nullptr,
      nullptr,
      nullptr,
      nullptr,
      colours.data(),
      styles.data(),
      widths.data(),
      nullptr,
      nullptr,
      nullptr,
      nullptr);
}

/// A timeline: lanes top to bottom, bars stacked within a lane where they overlap. `height`: the
/// panel's pixels (the margins for the axis and title are fixed in pixels).
void draw_lanes(const PlotPanel& panel, int height) {
  double x_min = std::numeric_limits<double>::infinity();
  double x_max = -x_min;
  bool labels = false;
  for (const auto& lane : panel.lanes) {
    labels = labels || !lane.label.empty();
    for (const auto& b : lane.bars) {
      x_min = std::min({x_min, b.x0, b.x1});
      x_max = std::max({x_max, b.x0, b.x1});
    }
    if (lane.span_end >= lane.span_begin) {
      x_min = std::min(x_min, lane.span_begin);
      x_max = std::max(x_max, lane.span_end);
    }
  }
  if (!std::isfinite(x_min)) x_min = 0, x_max = 1;
  if (x_max <= x_min) x_max = x_min + 1;
  const double pad = 0.02 * (x_max - x_min);
  x_min -= pad;
  x_max += pad;
  if (panel.x_max > panel.x_min) {
    x_min = panel.x_min;
    x_max = panel.x_max;
  }
  const double min_width = 0.004 * (x_max - x_min);
  const auto n = static_cast<double>(std::max<std::size_t>(panel.lanes.size(), 1));
  pladv(0);
  if (labels) {
    const double h = std::max(height, 100);
    plvpor(0.22, 0.97, 60.0 / h, 1.0 - 45.0 / h);
  } else {
    plvsta();
  }
  plwind(x_min, x_max, 0.0, n);
  plcol0(kGridColour);
  plbox("g", 0.0, 0, "", 0.0, 0);
  plcol0(1);
  plbox("bcnst", 0.0, 0, "bc", 0.0, 0);
  pllab(panel.x_label.c_str(), panel.y_label.c_str(), panel.title.c_str());
  for (std::size_t i = 0; i < panel.lanes.size(); ++i) {
    const auto& lane = panel.lanes[i];
    const double bottom = n - 1.0 - static_cast<double>(i);
    if (i > 0) {
      plcol0(kGridColour);
      pljoin(x_min, bottom + 1.0, x_max, bottom + 1.0);
    }
    plcol0(1);
    if (!lane.label.empty()) plmtex("lv", 0.8, (bottom + 0.5) / n, 1.0, lane.label.c_str());
    if (lane.span_end >= lane.span_begin) {
      plcol0(kSpanColour);
      plwidth(2.0);
      pljoin(lane.span_begin, bottom + 0.05, lane.span_end, bottom + 0.05);
      plwidth(1.0);
    }
    // Overlapping bars go on rows of their own within the lane (first row that is free).
    std::vector<std::size_t> order(lane.bars.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return lane.bars[a].x0 < lane.bars[b].x0;
    });
    std::vector<double> row_end;
    std::vector<std::size_t> row_of(lane.bars.size());
    for (const auto k : order) {
      const auto& b = lane.bars[k];
      const double x0 = std::min(b.x0, b.x1);
      std::size_t r = 0;
      while (r < row_end.size() && row_end[r] >= x0) ++r;
      if (r == row_end.size()) row_end.push_back(0);
      row_end[r] = std::max({b.x0, b.x1, x0 + min_width});
      row_of[k] = r;
    }
    const double row_height = 0.8 / static_cast<double>(std::max<std::size_t>(row_end.size(), 1));
    for (std::size_t k = 0; k < lane.bars.size(); ++k) {
      const auto& b = lane.bars[k];
      double x0 = std::min(b.x0, b.x1);
      double x1 = std::max(b.x0, b.x1);
      if (x1 - x0 < min_width) {
        const double mid = 0.5 * (x0 + x1);
        x0 = mid - 0.5 * min_width;
        x1 = mid + 0.5 * min_width;
      }
      const double y0 = bottom + 0.1 + row_height * static_cast<double>(row_of[k]);
      const double y1 = y0 + 0.9 * row_height;
      // Clipped to the window by hand (a fill is not).
      x0 = std::max(x0, x_min);
      x1 = std::min(x1, x_max);
      if (x1 <= x0) continue;
      std::array<PLFLT, 4> xs{x0, x1, x1, x0};
      std::array<PLFLT, 4> ys{y0, y0, y1, y1};
      plcol0(kEventColourBase + ((b.colour % kEventColours) + kEventColours) % kEventColours);
      plfill(4, xs.data(), ys.data());
      if (!b.text.empty() && row_end.size() <= 6) {
        plcol0(1);
        plschr(0.0, 0.7);
        plptex(0.5 * (x0 + x1), 0.5 * (y0 + y1) - 0.1 * row_height, 1.0, 0.0, 0.5, b.text.c_str());
        plschr(0.0, 1.1);
      }
    }
  }
}

}  // namespace

void write_png_plot(
    const std::filesystem::path& path,
    std::span<const PlotPanel> panels,
    int width,
    int panel_height) {
  const std::string name = path.string();
  // PLplot itself first (opened on first use): without it no file is created. Then, as PLplot
  // reports a file it cannot open by exiting the process, the file's writability.
  (void)detail::plplot();
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
  plspage(0.0, 0.0, width, panel_height * rows, 0, 0);
  plscolbg(255, 255, 255);
  plscmap0n(kEventColourBase + kEventColours);
  plssub(1, rows);
  plinit();
  plscol0(1, 0, 0, 0);
  plscol0(kGridColour, 220, 220, 220);
  for (std::size_t i = 0; i < kSeriesColours.size(); ++i) {
    const auto& c = kSeriesColours[i];
    plscol0(static_cast<PLINT>(2 + i), c[0], c[1], c[2]);
  }
  plscol0(kSpanColour, 170, 170, 170);
  for (std::size_t i = 0; i < kEventPalette.size(); ++i) {
    const auto& c = kEventPalette[i];
    plscol0(kEventColourBase + static_cast<PLINT>(i), c.r, c.g, c.b);
  }
  plschr(0.0, 1.1);
  for (const auto& panel : panels) {
    if (panel.lanes.empty()) {
      draw_panel(panel);
    } else {
      draw_lanes(panel, panel_height);
    }
  }
  plend1();
  std::error_code ec;
  if (std::filesystem::file_size(path, ec) == 0 || ec) {
    throw IoError(name + ": PLplot wrote no image (is the pngcairo device installed?)");
  }
}

void write_log_plot(
    const std::filesystem::path& path, const LogData& log, const std::string& title) {
  PlotSeries dcd_pairs{"DCD pairs (per sample)", {}, {}};
  PlotSeries ccd_contacts{"CCD contacts (per interval)", {}, {}};
  PlotSeries dcd_candidates{"DCD rows", {}, {}};
  PlotSeries ccd_candidates{"CCD rows", {}, {}};
  PlotSeries dcd_ms{"DCD rows", {}, {}};
  PlotSeries ccd_ms{"CCD rows", {}, {}};
  // A labelled log (docs/events.md): the new findings too, those of its events.
  const bool labelled = !log.header.baseline.empty();
  PlotSeries new_pairs{"new DCD pairs", {}, {}};
  PlotSeries new_contacts{"new CCD contacts", {}, {}};
  for (const auto& row : log.frames) {
    const auto& c = row.counters;
    if (row.kind == QueryKind::dcd) {
      const double x = row.sample;
      dcd_pairs.x.push_back(x);
      dcd_pairs.y.push_back(static_cast<double>(c.dcd_pairs));
      if (labelled) {
        new_pairs.x.push_back(x);
        new_pairs.y.push_back(static_cast<double>(c.new_dcd_pairs));
      }
      dcd_candidates.x.push_back(x);
      dcd_candidates.y.push_back(static_cast<double>(c.candidate_pairs));
      dcd_ms.x.push_back(x);
      dcd_ms.y.push_back(row.total_us / 1000.0);
    } else {
      const double x = row.sample + 0.5;  // the interval's midpoint
      ccd_contacts.x.push_back(x);
      ccd_contacts.y.push_back(static_cast<double>(c.vf_contacts + c.ee_contacts));
      if (labelled) {
        new_contacts.x.push_back(x);
        new_contacts.y.push_back(static_cast<double>(c.new_ccd_contacts));
      }
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
  std::vector<PlotPanel> panels{
      {title + " — findings",
       "sample",
       "count",
       keep({dcd_pairs, ccd_contacts, new_pairs, new_contacts}),
       {}},
      {"candidate triangle pairs", "sample", "pairs", keep({dcd_candidates, ccd_candidates}), {}},
      {"time per frame", "sample", "ms", keep({dcd_ms, ccd_ms}), {}},
  };
  if (log.events_recorded && !log.events.empty()) {
    // One lane; events that overlap in time stack within it. A bar covers its samples.
    PlotLane lane;
    for (const auto& e : log.events) {
      lane.bars.push_back(
          PlotBar{e.first_sample - 0.4, e.last_sample + 0.4, e.id, std::to_string(e.id)});
    }
    if (!log.frames.empty()) {
      lane.span_begin = log.frames.front().sample;
      lane.span_end = log.frames.back().sample + (log.frames.back().kind == QueryKind::ccd ? 1 : 0);
    }
    // The x range of the panels above, so that the bars sit under their samples.
    double x_min = std::numeric_limits<double>::infinity();
    double x_max = -x_min;
    for (const auto& panel : panels) {
      for (const auto& series : panel.series) {
        for (const double x : series.x) x_min = std::min(x_min, x), x_max = std::max(x_max, x);
      }
    }
    panels.push_back(PlotPanel{
        "collision events (bars: first to last sample, by event id)",
        "sample",
        "",
        {},
        {lane},
        x_min,
        x_max});
  }
  write_png_plot(path, panels);
}

void write_events_timeline(
    const std::filesystem::path& path,
    const std::vector<PlotLane>& lanes,
    const std::string& title) {
  const std::vector<PlotPanel> panels{PlotPanel{
      title + " (bars: first to last sample, by event id; grey: the time checked)",
      "time (s)",
      "",
      {},
      lanes,
      0,
      0}};
  const int height = std::max(300, 100 + 40 * static_cast<int>(lanes.size()));
  write_png_plot(path, panels, 1000, height);
}

}  // namespace skelcd::tools
