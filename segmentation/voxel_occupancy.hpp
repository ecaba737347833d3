#pragma once
// A coarse voxel field of where the mesh is: each cell outside, on the surface, or inside. It is
// the paper's "coarse discrete distance field" (§4.1) reduced to what the heat weights use it for:
// deciding whether a segment from a vertex to a bone stays within the body.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "skinning/mesh.hpp"

namespace skelcd::segmentation {

enum class Cell : std::uint8_t { outside, surface, inside };

class VoxelOccupancy {
 public:
  /// Voxelises the mesh: cells of side h = (longest side of the bounding box) / resolution, one
  /// cell of margin around the box. Cells a triangle touches (exact triangle–box separating-axis
  /// test) are surface; a 6-connected flood fill from the margin through non-surface cells marks
  /// outside; the rest is inside.
  /// @param V #W × 3 positions; @param F #F × 3 indices.
  /// @pre resolution >= 1, the mesh has at least one triangle.
  /// @note A hole wider than a cell lets the fill in: that body's cells are then outside, and
  ///   segments through it are not visible (the heat weights fall back to the nearest bone).
  VoxelOccupancy(const skinning::Positions& V, const skinning::Triangles& F, int resolution);

  /// The cell containing `p` (outside for points beyond the grid).
  [[nodiscard]] Cell at(const Eigen::Vector3d& p) const;
  /// True when no point sampled every half cell along the segment a → b lies in an outside cell.
  [[nodiscard]] bool segment_inside(const Eigen::Vector3d& a, const Eigen::Vector3d& b) const;

  [[nodiscard]] double cell_size() const { return h_; }
  [[nodiscard]] Eigen::Vector3i dims() const { return dims_; }
  [[nodiscard]] std::int64_t count(Cell kind) const;

 private:
  [[nodiscard]] std::int64_t index(int x, int y, int z) const {
    return (static_cast<std::int64_t>(z) * dims_.y() + y) * dims_.x() + x;
  }
  Eigen::Vector3d origin_;
  Eigen::Vector3i dims_;
  double h_ = 1.0;
  std::vector<Cell> cells_;
};

/// Taubin λ|μ smoothing (λ = 0.5, μ = −0.53, uniform umbrella weights over edge neighbours),
/// `iterations` pairs of steps: removes fine detail without the shrinking of plain Laplacian
/// smoothing. Vertices in no triangle stay put.
/// @param V #W × 3; @param F #F × 3.  @return #W × 3 smoothed positions.
[[nodiscard]] skinning::Positions taubin_smooth(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    int iterations);

}  // namespace skelcd::segmentation
