#pragma once
// The triangle mesh every stage works on, as imported: file vertices (not welded) and triangles,
// with the map back to the file's own numbering (part and index) for reporting.
// A field added to Mesh must also cross from the import's child process to its parent:
// skinning/detail/imported_rig_stream.cpp, and the comparison in its test.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace skelcd::skinning {

/// #V × 3 vertex positions, one row per vertex.
using Positions = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// #F × 3 vertex indices, one row per triangle, counter-clockwise seen from outside.
using Triangles = Eigen::Matrix<std::int32_t, Eigen::Dynamic, 3, Eigen::RowMajor>;

/// A triangle mesh made of one or more parts (the meshes of a file, the links of a robot).
struct Mesh {
  /// #V × 3 rest (bind) positions in object space: node transforms and unit scale applied.
  Positions rest_positions;
  /// #F × 3 indices into rest_positions.
  Triangles triangles;
  /// #F part id of each triangle (index into part_names).
  std::vector<std::int32_t> face_part;
  /// #F index of each triangle within its part in the file.
  std::vector<std::int32_t> face_index_in_part;
  /// #V part id of each vertex.
  std::vector<std::int32_t> vertex_part;
  /// #V index of each vertex within its part in the file.
  std::vector<std::int32_t> vertex_index_in_part;
  /// One name per part (the mesh or link name in the file).
  std::vector<std::string> part_names;
  /// Pairs of parts (a <= b) whose triangles are never checked against each other, e.g. a robot's
  /// parent-child links and SRDF-disabled pairs; (a, a) means "no self-check within part a"
  /// (a rigid link cannot deform into itself).
  std::vector<std::pair<std::int32_t, std::int32_t>> excluded_part_pairs;

  [[nodiscard]] std::int64_t num_vertices() const { return rest_positions.rows(); }
  [[nodiscard]] std::int64_t num_triangles() const { return triangles.rows(); }
  [[nodiscard]] std::int32_t num_parts() const {
    return static_cast<std::int32_t>(part_names.size());
  }
};

/// Throws InvalidInput naming `source` and the first offending index when the mesh is not usable:
/// non-finite coordinates, indices out of range, mismatched per-face or per-vertex arrays.
void validate_mesh(const Mesh& mesh, const std::string& source);

}  // namespace skelcd::skinning
