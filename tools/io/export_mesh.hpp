#pragma once
// Writing a posed mesh to OBJ or glTF binary through assimp's exporter, or to binary PLY (written
// here: Debian 12's assimp writes corrupt coloured PLY) — for viewers.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::tools {

enum class MeshFormat { obj, ply, glb };

/// "obj" | "ply" | "glb" (also as a file extension, with or without the dot, any case).
[[nodiscard]] std::optional<MeshFormat> parse_mesh_format(std::string name);

/// True for "-" and "/dev/stdout": the mesh goes to standard output.
[[nodiscard]] bool is_stdout(const std::filesystem::path& path);

struct ExportOptions {
  /// Format; unset: from the output's extension (required then, unless writing to stdout,
  /// where OBJ is the default).
  std::optional<MeshFormat> format;
  /// #F RGBA colours in [0, 1], one per triangle, or empty. With colours, every triangle gets
  /// its own three vertices so that a face's colour does not bleed into its neighbours (PLY and
  /// glb carry vertex colours; OBJ has none). Meant for highlighting colliding triangles or
  /// showing a segmentation.
  std::vector<std::array<float, 4>> face_colors;
};

struct ExportResult {
  MeshFormat format = MeshFormat::obj;
  std::int64_t triangles = 0;
  std::int64_t vertices = 0;  ///< as written
  std::int64_t bytes = 0;
};

/// Writes `mesh` with `positions` to `out`: one mesh per part (named as the part), triangles
/// as in the Mesh. A file is written to a temporary name beside it and renamed when complete,
/// so a failure never leaves a partial file.
/// @param positions #V × 3 (rows of mesh.rest_positions posed).
/// @throws InvalidInput on a bad format, shape or colour count; IoError when writing fails.
ExportResult export_mesh(
    const skinning::Mesh& mesh,
    const skinning::Positions& positions,
    const std::filesystem::path& out,
    const ExportOptions& options = {});

}  // namespace skelcd::tools
