#pragma once
// Topology of a Mesh, built once: vertices welded by position (seams in real assets duplicate
// vertices; without welding every seam would look like a boundary), unique edges with their incident
// faces, face adjacency, boundary edges and loops, connected components marked closed or open, and
// the problems found (non-manifold edges, degenerate triangles).

#include <array>
#include <cstdint>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::skinning {

/// #E × 2 welded vertex ids of each unique edge, smaller id first.
using Edges = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 2, Eigen::RowMajor>;

struct Component {
  std::vector<std::int32_t> faces;  ///< triangle ids of this edge-connected component
  bool closed = false;              ///< no boundary edge and no non-manifold edge
  std::int32_t part = -1;           ///< part of its first triangle
};

struct Topology {
  /// #V welded id of each file vertex.
  std::vector<std::int32_t> welded_of_vertex;
  /// #W one file vertex per welded vertex (the first in file order).
  std::vector<std::int32_t> representative_vertex;
  /// #F × 3 triangles in welded ids (same order and orientation as Mesh::triangles).
  Triangles welded_triangles;
  /// #E × 2 unique edges in welded ids: edges(e, 0) < edges(e, 1), sorted by that pair (ghost
  /// caps pair the edges of two topologies by merging the two lists).
  Edges edges;
  /// #F × 3: face_edges(f, k) is the edge from corner k to corner (k+1) % 3.
  Triangles face_edges;
  /// CSR incidence edge → faces: the faces of edge e are
  /// edge_faces[edge_face_offsets[e] .. edge_face_offsets[e+1]).
  std::vector<std::int32_t> edge_face_offsets;
  std::vector<std::int32_t> edge_faces;
  /// #F × 3: the face across side k of face f, or -1 on a boundary (first other face when
  /// the edge is non-manifold).
  Triangles face_adjacency;
  /// Edges with exactly one incident face.
  std::vector<std::int32_t> boundary_edges;
  /// Closed loops of welded vertex ids along boundary edges (each loop listed once).
  std::vector<std::vector<std::int32_t>> boundary_loops;
  /// Edge-connected components; face_component[f] indexes into components.
  std::vector<Component> components;
  std::vector<std::int32_t> face_component;
  /// Edges with three or more incident faces.
  std::vector<std::int32_t> non_manifold_edges;
  /// Triangles with a repeated welded index or zero area (exact test) at rest.
  std::vector<std::int32_t> degenerate_triangles;

  [[nodiscard]] std::int32_t num_welded_vertices() const {
    return static_cast<std::int32_t>(representative_vertex.size());
  }
  [[nodiscard]] std::int32_t num_edges() const { return static_cast<std::int32_t>(edges.rows()); }
};

struct WeldOptions {
  /// Vertices whose rest positions are equal (bit for bit) are welded. Positions are compared
  /// exactly: seams duplicate the same coordinates, and a distance threshold would merge
  /// vertices that are merely close.
  bool weld = true;
};

/// Builds the topology of `mesh`.
/// @throws InvalidInput when the mesh fails validate_mesh.
[[nodiscard]] Topology build_topology(const Mesh& mesh, const WeldOptions& options = {});

/// A boundary edge as its one triangle runs it (from → to, welded ids).
struct BoundarySide {
  std::int32_t from = -1;
  std::int32_t to = -1;
  std::int32_t face = -1;
};

/// The boundary loops a fan can close (radial view's ghost caps): the boundary sides, walked head
/// to tail, as simple cycles of 3 to `max_edges` sides in components without non-manifold edges —
/// a loop through a pinch vertex (two or more sides in and out) is split there into simple cycles,
/// each closed by its own fan; sides that do not close into a cycle (inconsistent orientation)
/// are left out. Each loop is its sides in order.
[[nodiscard]] std::vector<std::vector<BoundarySide>> small_simple_loops(
    const Topology& topology, std::int32_t max_edges);

/// The small_simple_loops worth closing with fans: those of the components whose every boundary
/// edge lies on such a loop (so that closing them closes the component) and that have at least
/// `triangles_per_side` triangles per side of those loops (a fan adds one triangle per side; on
/// a small part the fans' own pairs cost more than closing it saves). Each loop is its sides in
/// order, as small_simple_loops gives them.
[[nodiscard]] std::vector<std::vector<BoundarySide>> closing_loops(
    const Topology& topology, std::int32_t max_edges, std::int32_t triangles_per_side);

/// Gathers welded positions: row w of `welded` is row representative_vertex[w] of `positions`.
/// @param positions #V × 3 file-vertex positions.  @param welded resized to #W × 3.
void gather_welded(const Topology& topology, const Positions& positions, Positions& welded);

}  // namespace skelcd::skinning
