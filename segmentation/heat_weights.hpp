#pragma once
// Bone heat weights (Baran & Popović 2007, "Automatic rigging and animation of 3D characters",
// as the radial-view papers use them): for each bone j solve (−Δ + H) w_j = H p_j on the welded
// mesh, where Δ is the area-normalised cotangent Laplacian, H_ii = c / d_i² with d_i the distance
// from vertex i to the nearest bone it can see, and p_j(i) = 1 when that bone is j (1/k when k
// bones tie). The matrix is factorised once; each bone is one back-substitution.

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "segmentation/bone_segment.hpp"
#include "segmentation/laplacian.hpp"
#include "skinning/mesh.hpp"
#include "skinning/rig.hpp"

namespace skelcd::segmentation {

/// How the distance d_i to the nearest *visible* bone is found.
enum class DistanceMode : std::uint8_t {
  /// Per vertex: the segment from the vertex to the nearest point of a bone is visible when it
  /// crosses no triangle (exact positions, ray casts against a triangle BVH).
  exact,
  /// The paper's speed-up (§4.1): smooth the mesh, voxelise it coarsely, and call the segment
  /// visible when it runs through no outside cell of that voxel field.
  coarse,
};

struct HeatWeightsOptions {
  DistanceMode distance = DistanceMode::exact;
  /// c in H_ii = c / d_i² (dimensionless; Baran & Popović use 1).
  double heat_constant = 1.0;
  /// Bones whose visible distance is within (1 + tie_tolerance) of the nearest share the heat
  /// source of a vertex (relative, dimensionless; Pinocchio uses 1e-4).
  double tie_tolerance = 1e-4;
  /// d_i is clamped below to this fraction of the bounding-box diagonal, so that a vertex lying on
  /// a bone gets a large but finite H_ii (dimensionless).
  double min_distance_fraction = 1e-6;
  /// Coarse mode: cells along the longest side of the bounding box.
  int grid_resolution = 48;
  /// Coarse mode: Taubin λ|μ smoothing iterations applied before voxelising.
  int smoothing_iterations = 10;
  /// Distance queries and per-bone solves run in parallel (oneTBB); results are identical.
  bool parallel = true;
};

/// The heat source of every vertex: its distance to the nearest visible bone and which bones
/// (one, or several when they tie) that is.
struct HeatSources {
  /// #W distance d_i (coordinate units), before the min_distance clamp.
  Eigen::VectorXd distance;
  /// CSR: the source bones of vertex i are bones[offsets[i] .. offsets[i+1]), ascending.
  std::vector<std::int32_t> offsets;
  std::vector<std::int32_t> bones;
  /// Vertices that could see no bone and fell back to the nearest bone (visibility ignored).
  std::int64_t fallback_vertices = 0;
};

struct HeatWeightsStats {
  std::int64_t vertices = 0;
  std::int32_t bones = 0;
  /// Vertices that saw no bone (heat from the nearest bone regardless of visibility).
  std::int64_t fallback_vertices = 0;
  /// Vertices in no non-degenerate triangle: their weights are their heat source p_i directly.
  std::int64_t isolated_vertices = 0;
  std::int64_t degenerate_triangles = 0;
  /// Negative entries of the solution set to 0 before normalising (obtuse cotangents break the
  /// discrete maximum principle), and the most negative value met (0 when none).
  std::int64_t clamped_weights = 0;
  double most_negative_weight = 0.0;
  /// Coarse mode: voxel cell size (coordinate units) and grid dimensions; 0 in exact mode.
  double cell_size = 0.0;
  Eigen::Vector3i grid_dims = Eigen::Vector3i::Zero();
  /// Wall-clock seconds: distances/visibility, assembly + factorisation, solves + clean-up.
  double distance_s = 0.0;
  double factorize_s = 0.0;
  double solve_s = 0.0;
  [[nodiscard]] double total_s() const { return distance_s + factorize_s + solve_s; }
};

struct HeatWeights {
  /// #W × #B weights: non-negative, each row sums to 1.
  Eigen::MatrixXd weights;
  HeatWeightsStats stats;
};

/// Finds each vertex's heat source: the nearest bone it can see (see DistanceMode).
/// @param V #W × 3 rest positions (welded); @param F #F × 3; @param bones #B rest segments.
/// @param stats if not null, receives fallback_vertices, cell_size, grid_dims and distance_s.
/// @note In coarse mode distances and visibility are measured from the smoothed vertices.
[[nodiscard]] HeatSources nearest_visible_bones(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    const std::vector<BoneSegment>& bones,
    const HeatWeightsOptions& options = {},
    HeatWeightsStats* stats = nullptr);

/// Built once per rig: finds the heat sources, assembles M (−Δ + H) = −L + M H (symmetric
/// positive definite: every vertex has H_ii > 0) and factorises it (sparse LDLᵀ); then solves
/// per bone.
class HeatWeightsSolver {
 public:
  /// @param V #W × 3 welded rest positions; @param F #F × 3; @param bones #B rest segments.
  /// @throws InvalidInput when there is no bone, no triangle, a non-finite bone end or vertex,
  ///   an index out of range, or an option out of range.
  HeatWeightsSolver(
      const skinning::Positions& V,
      const skinning::Triangles& F,
      std::vector<BoneSegment> bones,
      const HeatWeightsOptions& options = {});
  ~HeatWeightsSolver();
  HeatWeightsSolver(const HeatWeightsSolver&) = delete;
  HeatWeightsSolver& operator=(const HeatWeightsSolver&) = delete;

  [[nodiscard]] std::int32_t num_bones() const;
  [[nodiscard]] const HeatSources& sources() const;
  [[nodiscard]] const CotangentLaplacian& laplacian() const;

  /// #W raw solution w_j of bone j (before clamping and normalising).
  /// @pre 0 <= bone < num_bones()
  [[nodiscard]] Eigen::VectorXd solve(std::int32_t bone) const;
  /// All bones: #W × #B, negatives clamped to 0, rows normalised to sum 1.
  [[nodiscard]] HeatWeights solve_all() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One shot: welds the rig's mesh (skinning::build_topology), solves the heat weights on it, and
/// returns them for the file vertices: #V × #B (welded copies get the same row).
/// @throws InvalidInput as HeatWeightsSolver, naming rig.source.
[[nodiscard]] HeatWeights heat_weights(
    const skinning::Rig& rig,
    const HeatWeightsOptions& options = {});

}  // namespace skelcd::segmentation
