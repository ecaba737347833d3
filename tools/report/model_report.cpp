#include "tools/report/model_report.hpp"

#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

namespace skelcd::tools {
namespace {

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

// A rate as people write it: 24, 29.97, 23.976, 0.8.
std::string rate(double hz) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6g", hz);
  return buffer;
}

// The phrase of a report's rate_source (skinning::to_string of a FrameRateSource).
std::string rate_source_phrase(const std::string& source) {
  using skinning::FrameRateSource;
  for (const auto s :
       {FrameRateSource::none,
        FrameRateSource::file,
        FrameRateSource::key_grid,
        FrameRateSource::trajectory_rows,
        FrameRateSource::frame_sequence,
        FrameRateSource::generator}) {
    if (source == skinning::to_string(s)) return skinning::describe(s);
  }
  return source;
}

// "triangle 12 (part 'Head', its triangle 3)": file numbering for the user.
std::string triangle_label(const skinning::Mesh& mesh, std::int32_t f) {
  const auto part = mesh.face_part[static_cast<std::size_t>(f)];
  return "triangle " + std::to_string(f) + " (part '" +
         mesh.part_names[static_cast<std::size_t>(part)] + "', its triangle " +
         std::to_string(mesh.face_index_in_part[static_cast<std::size_t>(f)]) + ")";
}

// "vertex 40 (part 'Head', its vertex 7)", as triangle_label.
std::string vertex_label(const skinning::Mesh& mesh, std::int32_t v) {
  const auto part = mesh.vertex_part[static_cast<std::size_t>(v)];
  return "vertex " + std::to_string(v) + " (part '" +
         mesh.part_names[static_cast<std::size_t>(part)] + "', its vertex " +
         std::to_string(mesh.vertex_index_in_part[static_cast<std::size_t>(v)]) + ")";
}

}  // namespace

nlohmann::json model_report(
    const skinning::LoadedModel& model, const skinning::Topology& topology) {
  const auto& mesh = *model.mesh;
  nlohmann::json j;
  j["file"] = model.path.string();
  j["kind"] = skinning::to_string(model.kind);
  j["triangles"] = mesh.num_triangles();
  j["vertices"] = mesh.num_vertices();
  j["welded_vertices"] = topology.num_welded_vertices();
  j["edges"] = topology.num_edges();
  j["bones"] = model.rig ? model.rig->skeleton.num_bones() : 0;
  j["nodes"] = model.rig ? model.rig->skeleton.nodes.size() : 0;
  j["clips"] = nlohmann::json::array();
  for (const auto& c : model.clips) {
    j["clips"].push_back(
        {{"name", c.name},
         {"duration_s", c.duration_s},
         {"keys_per_s", c.keys_per_s},
         {"rate_hz", c.rate_hz},
         {"rate_source", skinning::to_string(c.rate_source)}});
  }

  // Parts: a part is closed when every component its triangles belong to is closed.
  const auto np = static_cast<std::size_t>(mesh.num_parts());
  std::vector<std::int64_t> triangles(np, 0), vertices(np, 0);
  std::vector<bool> closed(np, true);
  std::vector<std::vector<std::int32_t>> components(np);
  for (std::size_t f = 0; f < mesh.face_part.size(); ++f) {
    const auto p = static_cast<std::size_t>(mesh.face_part[f]);
    ++triangles[p];
    const auto c = topology.face_component[f];
    if (!topology.components[static_cast<std::size_t>(c)].closed) closed[p] = false;
    if (components[p].empty() || components[p].back() != c) components[p].push_back(c);
  }
  for (const auto p : mesh.vertex_part) ++vertices[static_cast<std::size_t>(p)];
  j["parts"] = nlohmann::json::array();
  for (std::size_t p = 0; p < np; ++p) {
    auto& list = components[p];
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    j["parts"].push_back(
        {{"name", mesh.part_names[p]},
         {"triangles", triangles[p]},
         {"vertices", vertices[p]},
         {"closed", triangles[p] > 0 && closed[p]},
         {"components", list.size()}});
  }
  std::size_t closed_components = 0;
  for (const auto& c : topology.components) {
    if (c.closed) ++closed_components;
  }
  j["components"] = topology.components.size();
  j["closed_components"] = closed_components;
  j["boundary_edges"] = topology.boundary_edges.size();
  j["boundary_loops"] = topology.boundary_loops.size();
  j["non_manifold_edges"] = topology.non_manifold_edges.size();
  j["degenerate_triangles"] = topology.degenerate_triangles.size();
  j["unit_scale"] = model.unit_scale;
  j["rest_pose_deviation"] = model.rest_pose_deviation;
  if (mesh.num_vertices() > 0) {
    const Eigen::RowVector3d lo = mesh.rest_positions.colwise().minCoeff();
    const Eigen::RowVector3d hi = mesh.rest_positions.colwise().maxCoeff();
    j["bounding_box"] = {{"min", {lo(0), lo(1), lo(2)}}, {"max", {hi(0), hi(1), hi(2)}}};
  }

  nlohmann::json problems = nlohmann::json::array();
  for (const auto& p : model.problems) problems.push_back(p);
  if (!topology.non_manifold_edges.empty()) {
    const auto e = topology.non_manifold_edges.front();
    const auto a = topology.representative_vertex[static_cast<std::size_t>(topology.edges(e, 0))];
    const auto b = topology.representative_vertex[static_cast<std::size_t>(topology.edges(e, 1))];
    problems.push_back(
        std::to_string(topology.non_manifold_edges.size()) +
        " non-manifold edges (three or more triangles on one edge; first: between " +
        vertex_label(mesh, a) + " and " + vertex_label(mesh, b) + ")");
  }
  if (!topology.degenerate_triangles.empty()) {
    problems.push_back(
        std::to_string(topology.degenerate_triangles.size()) +
        " degenerate triangles (zero area or a repeated vertex; first: " +
        triangle_label(mesh, topology.degenerate_triangles.front()) + ")");
  }
  j["problems"] = problems;
  return j;
}

std::string format_model_report(const nlohmann::json& r) {
  std::ostringstream os;
  os << r["file"].get<std::string>() << " (" << r["kind"].get<std::string>() << ")\n";
  os << "  mesh:     " << r["triangles"] << " triangles, " << r["vertices"] << " vertices ("
     << r["welded_vertices"] << " after welding), " << r["edges"] << " edges\n";
  if (r.contains("bounding_box")) {
    const auto& lo = r["bounding_box"]["min"];
    const auto& hi = r["bounding_box"]["max"];
    os << "  extent:   " << fixed(hi[0].get<double>() - lo[0].get<double>(), 4) << " x "
       << fixed(hi[1].get<double>() - lo[1].get<double>(), 4) << " x "
       << fixed(hi[2].get<double>() - lo[2].get<double>(), 4);
    if (r["unit_scale"].get<double>() != 1.0)
      os << " (file units scaled by " << r["unit_scale"].get<double>() << ")";
    os << "\n";
  }
  os << "  skeleton: " << r["bones"] << " bones, " << r["nodes"] << " nodes\n";
  os << "  clips:    " << r["clips"].size() << "\n";
  for (const auto& c : r["clips"]) {
    os << "    " << c["name"].get<std::string>() << "  " << fixed(c["duration_s"].get<double>(), 3)
       << " s  " << fixed(c["keys_per_s"].get<double>(), 2) << " keys/s  sampled at "
       << rate(c["rate_hz"].get<double>()) << " Hz ("
       << rate_source_phrase(c["rate_source"].get<std::string>()) << ")\n";
  }
  std::size_t closed_parts = 0;
  for (const auto& p : r["parts"]) {
    if (p["closed"].get<bool>()) ++closed_parts;
  }
  os << "  parts:    " << r["parts"].size() << " (" << closed_parts << " closed)\n";
  for (const auto& p : r["parts"]) {
    os << "    " << p["name"].get<std::string>() << "  " << p["triangles"] << " triangles  "
       << (p["closed"].get<bool>() ? "closed" : "open") << "\n";
  }
  os << "  topology: " << r["components"] << " components (" << r["closed_components"]
     << " closed), " << r["boundary_loops"] << " boundary loops, " << r["non_manifold_edges"]
     << " non-manifold edges, " << r["degenerate_triangles"] << " degenerate triangles\n";
  os << "  problems: " << r["problems"].size() << "\n";
  for (const auto& p : r["problems"]) os << "    - " << p.get<std::string>() << "\n";
  return os.str();
}

}  // namespace skelcd::tools
