#pragma once
// Which triangles share an edge: edge → faces and face → neighbouring faces, from welded triangles.
// Every face on a non-manifold edge neighbours every other face on it.

#include <cstdint>
#include <vector>

#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {

struct FaceGraph {
  /// CSR edge → faces: the faces of edge e are edge_faces[edge_offsets[e] .. edge_offsets[e+1]),
  /// ascending; edges in ascending (smaller vertex, larger vertex) order.
  std::vector<std::int32_t> edge_offsets;
  std::vector<std::int32_t> edge_faces;
  /// CSR face → faces sharing at least one edge with it, ascending, without repeats.
  std::vector<std::int32_t> offsets;
  std::vector<std::int32_t> neighbours;

  [[nodiscard]] std::int32_t num_edges() const {
    return static_cast<std::int32_t>(edge_offsets.size()) - 1;
  }
};

/// Builds the face graph of F (#F × 3 welded vertex indices). Repeated-index triangles contribute
/// only their proper edges.
[[nodiscard]] FaceGraph face_graph(const skinning::Triangles& F);

/// The same graph as face_graph(topology.welded_triangles), from the edge lists the topology
/// already has (its edges are sorted the same way, their faces ascending, a folded triangle once).
[[nodiscard]] FaceGraph face_graph(const skinning::Topology& topology);

}  // namespace skelcd::segmentation
