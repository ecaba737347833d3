#include "tools/report/highlight.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <string>

#include "skinning/errors.hpp"
#include "skinning/topology.hpp"

namespace skelcd::tools {
namespace {

/// Relative difference under which two sample times (i / rate, in doubles) are the same.

/// (part, index within part) → row, for vertices or triangles.
std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> index_map(
    const std::vector<std::int32_t>& part, const std::vector<std::int32_t>& index_in_part) {
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> map;
  for (std::size_t i = 0; i < part.size(); ++i) {
    map.emplace(std::pair{part[i], index_in_part[i]}, static_cast<std::int32_t>(i));
  }
  return map;
}

}  // namespace

std::vector<std::int32_t> highlighted_triangles(
    const LogData& log, const skinning::Mesh& mesh, std::int32_t frame) {
  std::vector<std::int32_t> out;
  for (const auto& [f, label] : labelled_triangles(log, mesh, frame)) out.push_back(f);
  return out;
}

namespace {

/// Order of precedence of labels on one triangle: events by id, then baseline, allowed, none.
std::pair<int, std::int32_t> precedence(std::int32_t label) {
  if (label >= 0) return {0, label};
  if (label == kLabelBaseline) return {1, 0};
  if (label == kLabelAllowed) return {2, 0};
  return {3, 0};
}

}  // namespace

std::vector<std::pair<std::int32_t, std::int32_t>> labelled_triangles(
    const LogData& log, const skinning::Mesh& mesh, std::int32_t frame) {
  const auto& h = log.header;
  if (h.num_vertices != mesh.num_vertices() || h.num_triangles != mesh.num_triangles()) {
    throw InvalidInput(
        "the log was written for a mesh of " + std::to_string(h.num_vertices) + " vertices and " +
        std::to_string(h.num_triangles) + " triangles; this one has " +
        std::to_string(mesh.num_vertices()) + " and " + std::to_string(mesh.num_triangles()) +
        " (" + h.input_path + ")");
  }
  const auto faces = index_map(mesh.face_part, mesh.face_index_in_part);
  const auto vertices = index_map(mesh.vertex_part, mesh.vertex_index_in_part);
  const auto face_of = [&](const FeatureId& id) {
    const auto it = faces.find({id.part, id.index});
    if (it == faces.end()) {
      throw InvalidInput(
          "the log names triangle " + std::to_string(id.index) + " of part " +
          std::to_string(id.part) + ", which this mesh does not have");
    }
    return it->second;
  };

  // Welded incidence: the triangles around each welded vertex.
  const auto topology = skinning::build_topology(mesh);
  std::vector<std::vector<std::int32_t>> around(
      static_cast<std::size_t>(topology.num_welded_vertices()));
  for (Eigen::Index f = 0; f < topology.welded_triangles.rows(); ++f) {
    for (int k = 0; k < 3; ++k) {
      around[static_cast<std::size_t>(topology.welded_triangles(f, k))].push_back(
          static_cast<std::int32_t>(f));
    }
  }
  const auto welded = [&](std::int32_t file_vertex) {
    return static_cast<std::size_t>(
        topology.welded_of_vertex[static_cast<std::size_t>(file_vertex)]);
  };

  std::vector<std::pair<std::int32_t, std::int32_t>> out;  // (triangle, label)
  std::int32_t label = kLabelNone;                         // of the finding being added
  const auto add = [&](std::int32_t f) { out.emplace_back(f, label); };
  const auto add_around = [&](std::size_t w) {
    for (const auto f : around[w]) add(f);
  };
  for (const auto& p : log.dcd_pairs) {
    if (p.frame != frame) continue;
    label = p.label;
    add(face_of(p.a));
    add(face_of(p.b));
  }
  for (const auto& c : log.contacts) {
    if (c.frame != frame) continue;
    label = c.label;
    if (c.kind == culling::CcdContact::Kind::vf) {
      const auto it = vertices.find({c.a.part, c.a.index});
      if (it == vertices.end()) {
        throw InvalidInput(
            "the log names vertex " + std::to_string(c.a.index) + " of part " +
            std::to_string(c.a.part) + ", which this mesh does not have");
      }
      add_around(welded(it->second));
      add(face_of(c.b));
      continue;
    }
    // EE: an edge is side `side` of a triangle; mark the triangles sharing both its ends.
    for (const FeatureId& e : {c.a, c.b}) {
      const auto f = face_of(e);
      if (e.side < 0 || e.side > 2)
        throw InvalidInput("the log names an edge with side " + std::to_string(e.side));
      const auto w0 = welded(mesh.triangles(f, e.side));
      const auto w1 = welded(mesh.triangles(f, (e.side + 1) % 3));
      for (const auto t : around[w0]) {
        const auto& tri = around[w1];
        if (std::find(tri.begin(), tri.end(), t) != tri.end()) add(t);
      }
    }
  }
  // By triangle, the label of highest precedence first; then one entry per triangle.
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first < b.first : precedence(a.second) < precedence(b.second);
  });
  out.erase(
      std::unique(
          out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first == b.first; }),
      out.end());
  return out;
}

const PaletteColour& event_palette(std::int32_t event) {
  const auto n = static_cast<std::int32_t>(kEventPalette.size());
  return kEventPalette[static_cast<std::size_t>(((event % n) + n) % n)];
}

std::array<float, 4> label_colour(std::int32_t label) {
  if (label >= 0) {
    const auto& c = event_palette(label);
    return {c.r / 255.0f, c.g / 255.0f, c.b / 255.0f, 1.0f};
  }
  if (label == kLabelBaseline) return kBaselineColour;
  if (label == kLabelAllowed) return kAllowedColour;
  return kHighlightColour;
}

std::string legend(const Highlight& highlight) {
  if (highlight.triangles_per_label.empty()) return "no finding at this frame";
  std::string text;
  const auto add = [&](const std::string& item) { text += (text.empty() ? "" : ", ") + item; };
  const auto count = [](std::int64_t n) {
    return std::to_string(n) + (n == 1 ? " triangle" : " triangles");
  };
  // Events by id, then baseline, allowed, unlabelled.
  std::vector<std::pair<std::int32_t, std::int64_t>> entries(
      highlight.triangles_per_label.begin(), highlight.triangles_per_label.end());
  std::sort(entries.begin(), entries.end(), [](const auto& a, const auto& b) {
    return precedence(a.first) < precedence(b.first);
  });
  for (const auto& [label, n] : entries) {
    if (label >= 0) {
      add("event " + std::to_string(label) + " " + event_palette(label).name + ": " + count(n));
    } else if (label == kLabelBaseline) {
      add("baseline (slate): " + count(n));
    } else if (label == kLabelAllowed) {
      add("allowed (khaki): " + count(n));
    } else {
      add(count(n) + " in red");
    }
  }
  return text;
}

std::vector<std::array<float, 4>> highlight_face_colors(
    const std::filesystem::path& log_path,
    const skinning::Mesh& mesh,
    std::int32_t frame,
    double frame_time_s,
    std::string_view clip) {
  return highlight_frame(log_path, mesh, frame, frame_time_s, clip).face_colors;
}

Highlight highlight_frame(
    const std::filesystem::path& log_path,
    const skinning::Mesh& mesh,
    std::int32_t frame,
    double frame_time_s,
    std::string_view clip) {
  const auto log = read_log(log_path);
  const std::string where = log_path.string() + ": ";
  // A plain check log names its one clip; a scene log (several objects) is matched by the mesh.
  if (log.header.checks.empty() && !log.header.clip.empty() && log.header.clip != clip) {
    throw InvalidInput(
        where + "checked clip '" + log.header.clip + "', not '" + std::string(clip) +
        "': export with --clip " + log.header.clip);
  }
  // The log must have checked this very pose: a row for the sample, at the same time.
  const auto row = std::find_if(
      log.frames.begin(), log.frames.end(), [&](const FrameRow& r) { return r.sample == frame; });
  if (row == log.frames.end()) {
    throw InvalidInput(
        where + "no row for frame " + std::to_string(frame) + " (the log covers samples " +
        std::to_string(log.header.first_sample) + " to " + std::to_string(log.header.last_sample) +
        ")");
  }
  if (std::abs(row->t0 - frame_time_s) >
      kSampleTimeTolerance * std::max(1.0, std::abs(frame_time_s))) {
    char text[320];
    std::snprintf(
        text,
        sizeof text,
        "frame %d is at t = %.9g s in the log (written at %.9g samples/s) but at t = %.9g s here, "
        "%.3g s apart (more than the %.0e s allowed): pose it at the log's rate",
        frame,
        row->t0,
        log.header.fps,
        frame_time_s,
        std::abs(row->t0 - frame_time_s),
        kSampleTimeTolerance * std::max(1.0, std::abs(frame_time_s)));
    std::string message = text;
    if (log.header.fps > 0) {
      std::snprintf(text, sizeof text, " (--rate %.9g)", log.header.fps);
      message += text;
    }
    throw InvalidInput(where + message);
  }
  std::vector<std::pair<std::int32_t, std::int32_t>> hits;
  try {
    hits = labelled_triangles(log, mesh, frame);
  } catch (const InvalidInput& e) {
    throw InvalidInput(where + e.what());
  }
  Highlight out;
  // A log written before events has no labels: one colour, as it always had.
  out.labelled = !log.header.baseline.empty();
  out.face_colors.assign(static_cast<std::size_t>(mesh.num_triangles()), kPlainColour);
  for (const auto& [f, label] : hits) {
    const std::int32_t shown = out.labelled ? label : kLabelNone;
    out.face_colors[static_cast<std::size_t>(f)] = label_colour(shown);
    ++out.triangles_per_label[shown];
  }
  return out;
}

}  // namespace skelcd::tools
