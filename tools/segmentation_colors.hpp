#pragma once
// Per-triangle colours that show a saved segmentation in any viewer: one colour per atomic cluster.

#include <array>
#include <filesystem>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::tools {

/// One RGBA per triangle of `mesh`: the colour of its atomic cluster in the segmentation file
/// `path` (neighbouring cluster ids get well-separated hues, golden-ratio spacing).
/// @throws IoError when the file cannot be read as a segmentation; InvalidInput naming the file
///   when its triangle count differs from the mesh's.
[[nodiscard]] std::vector<std::array<float, 4>> segmentation_face_colors(
    const std::filesystem::path& path,
    const skinning::Mesh& mesh);

}  // namespace skelcd::tools
