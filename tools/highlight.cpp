#include "tools/highlight.hpp"

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
    const LogData& log,
    const skinning::Mesh& mesh,
    std::int32_t frame) {
  const auto& h = log.header;
  if (h.num_vertices != mesh.num_vertices() || h.num_triangles != mesh.num_triangles()) {
    throw InvalidInput("the log was written for a mesh of " + std::to_string(h.num_vertices) +
                       " vertices and " + std::to_string(h.num_triangles) +
                       " triangles; this one has " + std::to_string(mesh.num_vertices()) + " and " +
                       std::to_string(mesh.num_triangles()) + " (" + h.input_path + ")");
  }
  const auto faces = index_map(mesh.face_part, mesh.face_index_in_part);
  const auto vertices = index_map(mesh.vertex_part, mesh.vertex_index_in_part);
  const auto face_of = [&](const FeatureId& id) {
    const auto it = faces.find({id.part, id.index});
    if (it == faces.end()) {
      throw InvalidInput("the log names triangle " + std::to_string(id.index) + " of part " +
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
    return static_cast<std::size_t>(topology.welded_of_vertex[static_cast<std::size_t>(file_vertex)]);
  };

  std::vector<std::int32_t> out;
  const auto add_around = [&](std::size_t w) {
    out.insert(out.end(), around[w].begin(), around[w].end());
  };
  for (const auto& p : log.dcd_pairs) {
    if (p.frame != frame) continue;
    out.push_back(face_of(p.a));
    out.push_back(face_of(p.b));
  }
  for (const auto& c : log.contacts) {
    if (c.frame != frame) continue;
    if (c.kind == culling::CcdContact::Kind::vf) {
      const auto it = vertices.find({c.a.part, c.a.index});
      if (it == vertices.end()) {
        throw InvalidInput("the log names vertex " + std::to_string(c.a.index) + " of part " +
                           std::to_string(c.a.part) + ", which this mesh does not have");
      }
      add_around(welded(it->second));
      out.push_back(face_of(c.b));
      continue;
    }
    // EE: an edge is side `side` of a triangle; mark the triangles sharing both its ends.
    for (const FeatureId& e : {c.a, c.b}) {
      const auto f = face_of(e);
      if (e.side < 0 || e.side > 2) throw InvalidInput("the log names an edge with side " +
                                                       std::to_string(e.side));
      const auto w0 = welded(mesh.triangles(f, e.side));
      const auto w1 = welded(mesh.triangles(f, (e.side + 1) % 3));
      for (const auto t : around[w0]) {
        const auto& tri = around[w1];
        if (std::find(tri.begin(), tri.end(), t) != tri.end()) out.push_back(t);
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::vector<std::array<float, 4>> highlight_face_colors(
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
  const auto row = std::find_if(log.frames.begin(), log.frames.end(),
                                [&](const FrameRow& r) { return r.sample == frame; });
  if (row == log.frames.end()) {
    throw InvalidInput(where + "no row for frame " + std::to_string(frame) + " (the log covers samples " +
                       std::to_string(log.header.first_sample) + " to " +
                       std::to_string(log.header.last_sample) + ")");
  }
  if (std::abs(row->t0 - frame_time_s) > kSampleTimeTolerance * std::max(1.0, std::abs(frame_time_s))) {
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
  std::vector<std::int32_t> hits;
  try {
    hits = highlighted_triangles(log, mesh, frame);
  } catch (const InvalidInput& e) {
    throw InvalidInput(where + e.what());
  }
  std::vector<std::array<float, 4>> colours(static_cast<std::size_t>(mesh.num_triangles()),
                                            kPlainColour);
  for (const auto f : hits) colours[static_cast<std::size_t>(f)] = kHighlightColour;
  return colours;
}

}  // namespace skelcd::tools
