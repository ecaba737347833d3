#include "clustering/ghost_caps.hpp"

#include <algorithm>
#include <utility>

namespace skelcd::clustering {
namespace {

std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

}  // namespace

std::unique_ptr<GhostCaps> cap_small_loops(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation& segmentation,
    std::int32_t max_loop,
    std::int32_t triangles_per_ghost) {
  const auto num_faces = static_cast<std::int32_t>(topology.welded_triangles.rows());
  const std::int32_t num_welded = topology.num_welded_vertices();
  if (topology.boundary_edges.empty() ||
      static_cast<std::int32_t>(segmentation.triangle_cluster.size()) != num_faces ||
      mesh.num_triangles() != num_faces) {
    return nullptr;
  }
  const auto loops_found = skinning::closing_loops(topology, max_loop, triangles_per_ghost);
  if (loops_found.empty()) return nullptr;
  auto caps = std::make_unique<GhostCaps>();
  caps->real_vertices = num_welded;
  caps->real_triangles = num_faces;
  caps->loop_offsets.push_back(0);
  std::vector<std::pair<skinning::BoundarySide, std::int32_t>> ghost_sides;  // (side, centre)
  for (const auto& loop : loops_found) {
    const std::int32_t centre = caps->num_loops();
    for (const auto& side : loop) {
      caps->loop_vertices.push_back(side.from);
      ghost_sides.emplace_back(side, centre);
    }
    caps->loop_offsets.push_back(static_cast<std::int32_t>(caps->loop_vertices.size()));
  }

  // The capped mesh: centres after the file vertices, ghosts (to, from, centre) after the
  // triangles — the loop edge reversed, so that the orientation stays consistent.
  skinning::Mesh& m = caps->mesh;
  m = mesh;
  const auto num_file = static_cast<Eigen::Index>(mesh.num_vertices());
  const std::int32_t loops = caps->num_loops();
  // The centres at rest, as every query places them.
  skinning::Positions welded_rest, capped_rest;
  skinning::gather_welded(topology, mesh.rest_positions, welded_rest);
  place_ghost_centres(*caps, welded_rest, capped_rest);
  m.rest_positions.conservativeResize(num_file + loops, 3);
  for (std::int32_t j = 0; j < loops; ++j) {
    m.rest_positions.row(num_file + j) = capped_rest.row(num_welded + j);
    const auto first = caps->loop_offsets[at(j)];
    const auto any = topology.representative_vertex[at(caps->loop_vertices[at(first)])];
    m.vertex_part.push_back(mesh.vertex_part[at(any)]);
    m.vertex_index_in_part.push_back(-1);
  }
  const auto num_ghosts = static_cast<Eigen::Index>(ghost_sides.size());
  m.triangles.conservativeResize(num_faces + num_ghosts, 3);
  auto seg = std::make_shared<segmentation::Segmentation>(segmentation);
  for (Eigen::Index g = 0; g < num_ghosts; ++g) {
    const auto& [s, centre] = ghost_sides[static_cast<std::size_t>(g)];
    m.triangles(num_faces + g, 0) = topology.representative_vertex[at(s.to)];
    m.triangles(num_faces + g, 1) = topology.representative_vertex[at(s.from)];
    m.triangles(num_faces + g, 2) = static_cast<std::int32_t>(num_file + centre);
    m.face_part.push_back(mesh.face_part[at(s.face)]);
    m.face_index_in_part.push_back(-1);
    const std::int32_t cluster = segmentation.triangle_cluster[at(s.face)];
    seg->triangle_cluster.push_back(cluster);
    seg->clusters[at(cluster)].triangles.push_back(static_cast<std::int32_t>(num_faces + g));
  }
  caps->segmentation = std::move(seg);
  caps->topology = skinning::build_topology(m);
  // The real vertices keep their welded ids, each centre gets its own.
  const auto& t = caps->topology;
  if (t.num_welded_vertices() != num_welded + loops) return nullptr;
  for (Eigen::Index v = 0; v < num_file; ++v) {
    if (t.welded_of_vertex[static_cast<std::size_t>(v)] !=
        topology.welded_of_vertex[static_cast<std::size_t>(v)]) {
      return nullptr;
    }
  }
  for (std::int32_t j = 0; j < loops; ++j) {
    if (t.welded_of_vertex[static_cast<std::size_t>(num_file + j)] != num_welded + j) {
      return nullptr;
    }
  }
  // Edge ids: both topologies list their edges sorted by (smaller, larger) welded vertex, and
  // every edge between two real vertices of the capped mesh is a real edge (the ghosts add only
  // edges to their centres): one merge of the two sorted lists pairs them.
  caps->real_edge.assign(at(t.num_edges()), -1);
  const auto key = [](const skinning::Topology& topo, std::int32_t e) {
    return std::minmax(topo.edges(e, 0), topo.edges(e, 1));
  };
  std::int32_t r = 0;
  for (std::int32_t e = 0; e < t.num_edges(); ++e) {
    const auto k = key(t, e);
    if (k.second >= num_welded) continue;
    while (r < topology.num_edges() && key(topology, r) < k) ++r;
    if (r < topology.num_edges() && key(topology, r) == k) caps->real_edge[at(e)] = r;
  }
  return caps;
}

void place_ghost_centres(
    const GhostCaps& caps, const skinning::Positions& x, skinning::Positions& capped) {
  const std::int32_t loops = caps.num_loops();
  capped.resize(static_cast<Eigen::Index>(caps.real_vertices + loops), 3);
  capped.topRows(x.rows()) = x;
  for (std::int32_t j = 0; j < loops; ++j) {
    Eigen::RowVector3d sum = Eigen::RowVector3d::Zero();
    const auto first = caps.loop_offsets[at(j)];
    const auto last = caps.loop_offsets[at(j) + 1];
    for (auto i = first; i < last; ++i) {
      sum += x.row(static_cast<Eigen::Index>(caps.loop_vertices[at(i)]));
    }
    capped.row(static_cast<Eigen::Index>(caps.real_vertices + j)) =
        sum / static_cast<double>(last - first);
  }
}

}  // namespace skelcd::clustering
