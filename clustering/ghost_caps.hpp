#pragma once
// Ghost caps (docs/radial-view.md, "Open parts with ghost triangles"): the radial-view argument
// needs a closed surface, and real characters have small holes — eye sockets, cuffs, a neck
// opening, the end of a robot's tube. Each small boundary loop is closed with a fan of ghost
// triangles around a centre vertex that is the mean of the loop's vertices (so it moves linearly
// when they do). The ghosts take part in everything the guard does — cuts, patches, winding
// numbers, contacts that trigger re-tests — but their own findings are never reported.

#include <cstdint>
#include <memory>
#include <vector>

#include "segmentation/segmentation.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::clustering {

/// Boundary loops up to this many edges are capped (eye sockets, cuffs, a robot tube's end);
/// longer ones (a garment's hem) would cut much of the mesh.
inline constexpr std::int32_t kMaxGhostLoop = 64;
/// A part is capped only when it has at least this many triangles per ghost triangle (one per
/// loop side): on a small part the ghosts' own pairs cost more than what its skipped pairs save.
/// Testwuson's 53 open parts of 4 to 60 triangles, capped, made `dynamic` slower than `bvh` (6.6
/// against 5.3 ms per interval); left open, 3.9 ms.
inline constexpr std::int32_t kMinTrianglesPerGhost = 8;

struct GhostCaps {
  /// The mesh with the ghost centres appended after its vertices and the ghost triangles after its
  /// triangles, its welded topology (the real vertices and triangles keep their welded ids) and
  /// the segmentation with each ghost triangle in the cluster of the real triangle across its
  /// loop edge.
  skinning::Mesh mesh;
  skinning::Topology topology;
  std::shared_ptr<const segmentation::Segmentation> segmentation;
  std::int32_t real_vertices = 0;   ///< welded vertices of the real mesh
  std::int32_t real_triangles = 0;  ///< triangles of the real mesh
  /// CSR centre → its loop's welded vertices: centre j (welded id real_vertices + j) is the mean
  /// of loop_vertices[loop_offsets[j] .. loop_offsets[j + 1]).
  std::vector<std::int32_t> loop_offsets, loop_vertices;
  /// Edge of `topology` → the same edge of the real topology, −1 for a ghost's spoke.
  std::vector<std::int32_t> real_edge;

  [[nodiscard]] std::int32_t num_loops() const {
    return static_cast<std::int32_t>(loop_offsets.size()) - 1;
  }
};

/// Caps the boundary loops skinning::closing_loops(topology, max_loop, triangles_per_ghost)
/// gives: simple cycles of at most `max_loop` edges (split at pinch vertices) in components
/// without non-manifold edges, every hole of the component such a loop, and the component at
/// least `triangles_per_ghost` triangles per loop side. nullptr when no loop qualifies, when the
/// segmentation does not fit the mesh (the caller reports that), or when a centre would weld onto
/// an existing vertex.
[[nodiscard]] std::unique_ptr<GhostCaps> cap_small_loops(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation& segmentation,
    std::int32_t max_loop,
    std::int32_t triangles_per_ghost = kMinTrianglesPerGhost);

/// Rows [0, real_vertices) of `capped` are `x` (welded positions of the real mesh), the rest the
/// centres (means of their loops, in a fixed order of summation). Allocation-free once sized.
void place_ghost_centres(
    const GhostCaps& caps, const skinning::Positions& x, skinning::Positions& capped);

}  // namespace skelcd::clustering
