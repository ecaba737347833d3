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

/// Caps every boundary loop of at most `max_loop` edges that is a simple cycle (each of its
/// vertices on exactly two boundary edges, oriented head to tail) in a component without
/// non-manifold edges. nullptr when no loop qualifies, when the segmentation does not fit the mesh
/// (the caller reports that), or when a centre would weld onto an existing vertex.
[[nodiscard]] std::unique_ptr<GhostCaps> cap_small_loops(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const segmentation::Segmentation& segmentation,
    std::int32_t max_loop);

/// Rows [0, real_vertices) of `capped` are `x` (welded positions of the real mesh), the rest the
/// centres (means of their loops, in a fixed order of summation). Allocation-free once sized.
void place_ghost_centres(
    const GhostCaps& caps, const skinning::Positions& x, skinning::Positions& capped);

}  // namespace skelcd::clustering
