#pragma once
// The order a mesh's vertices and triangles are held in. Files store them in whatever order their
// writer chose: a simulator's cloth (the cloth-ball step) scatters the corners of one triangle
// over the whole vertex array. The checks read the triangles of one region together (the
// hierarchy's leaves, the feature stage's corners), so a file order without locality misses the
// caches on most reads. A spatial order puts what lies together in space together in memory; the
// file's numbering stays in Mesh::face_index_in_part and vertex_index_in_part, which every
// finding is reported in (docs/formats.md, "Frame sequences").

#include <cstdint>
#include <string>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::skinning {

/// The order a loader holds a mesh in.
enum class MeshOrder {
  file,     ///< vertices and triangles as the file lists them
  spatial,  ///< spatial_order: triangles along a space-filling curve, vertices by first use
};

/// A reordering of a mesh: position i of the new order holds old element faces[i] (vertices[i]).
struct MeshPermutation {
  std::vector<std::int32_t> faces;
  std::vector<std::int32_t> vertices;
};

/// Triangles sorted by the Morton code of their centroids (21 bits an axis over the bounding box of
/// the centroids; ties in the old order), vertices in the order the sorted triangles first use
/// them, then those no triangle uses, in the old order. Deterministic. An axis whose extent a
/// double cannot hold counts as one cell. Empty when a coordinate of a used vertex is not finite
/// or an index is out of range (validate_mesh refuses such a mesh later; the caller then keeps the
/// old order).
[[nodiscard]] MeshPermutation spatial_order(const Positions& positions, const Triangles& triangles);

/// The permutation that puts `mesh` back in its files' order — triangles by (face_part,
/// face_index_in_part), vertices by (vertex_part, vertex_index_in_part) — or an empty one when the
/// mesh is in that order already (every loader's order but MeshOrder::spatial).
[[nodiscard]] MeshPermutation file_order(const Mesh& mesh);

/// Rows of `from` in the order `rows` lists them (out.row(i) = from.row(rows[i])).
void gather_rows(const Positions& from, const std::vector<std::int32_t>& rows, Positions& out);

/// Labels every triangle and vertex of `mesh` (its rest_positions and triangles set) as one part
/// named `name` in file order: part 0, each element at its own index (a frame sequence, a
/// generated mesh).
void label_one_part_in_file_order(Mesh& mesh, std::string name);

/// `mesh` with its vertices and triangles in the order `p` gives (both complete permutations):
/// the triangles' corners renumbered, every per-vertex and per-face array moved with its element,
/// so face_index_in_part and vertex_index_in_part still name each element as the file does.
[[nodiscard]] Mesh reordered(const Mesh& mesh, const MeshPermutation& p);

}  // namespace skelcd::skinning
