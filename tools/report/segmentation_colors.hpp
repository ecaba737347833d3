#pragma once
// Per-triangle colours that show a saved segmentation in any viewer: one colour per atomic cluster,
// and the triangles not positively oriented to their cluster's observer in the rest pose marked by
// a dark shade of their cluster's colour.

#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "skinning/mesh.hpp"

namespace skelcd::tools {

/// Value (HSV) of a cluster's colour on its positively oriented triangles, and on the others.
inline constexpr double kPositiveValue = 0.95;
inline constexpr double kNonPositiveValue = 0.30;

struct SegmentationColors {
  /// #F RGBA, one per triangle of the mesh.
  std::vector<std::array<float, 4>> face_colors;
  /// Triangles in H⁻ or Hᵘ of their cluster's observer in the rest pose (the rest-pose |H⁻| + |Hᵘ|
  /// that `preprocess` reports), drawn dark.
  std::vector<std::int32_t> non_positive;
};

/// Colours of the segmentation file `path` on `mesh`: the colour of each triangle's atomic
/// cluster (neighbouring cluster ids get well-separated hues, golden-ratio spacing), bright
/// (value kPositiveValue) where the triangle is positively oriented to the cluster's observer in
/// the rest pose, dark (kNonPositiveValue) where it is not (exact orientation sign).
/// @throws IoError when the file cannot be read as a segmentation; InvalidInput naming the file
///   when its triangle count differs from the mesh's.
[[nodiscard]] SegmentationColors segmentation_colors(
    const std::filesystem::path& path, const skinning::Mesh& mesh);

/// segmentation_colors(path, mesh).face_colors.
[[nodiscard]] std::vector<std::array<float, 4>> segmentation_face_colors(
    const std::filesystem::path& path, const skinning::Mesh& mesh);

}  // namespace skelcd::tools
