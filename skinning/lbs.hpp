#pragma once
// Linear blend skinning: posed(v) = Σ_b W(v, b) · T_b · rest(v).

#include <cstdint>
#include <span>

#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"
#include "skinning/rig.hpp"

namespace skelcd::skinning {

/// Poses `rest_positions` with `weights` and one transform per weight column.
/// A vertex whose weight row is empty keeps its rest position.
/// @param rest_positions #V × 3 rest positions (object space).
/// @param weights #V × #T, rows normalised (or empty).
/// @param transforms #T transforms, object-space rest → object-space posed.
/// @param out #V × 3 posed positions; resized only when its shape differs, so a reused buffer
///            makes the call allocation-free.
/// @pre weights.rows() == rest_positions.rows(), weights.cols() <= transforms.size().
/// @note Not aliasing-safe: `out` must not be `rest_positions`.
void linear_blend_skinning(
    const Positions& rest_positions,
    const SkinWeights& weights,
    std::span<const BoneTransform> transforms,
    Positions& out);

/// linear_blend_skinning for some vertices only: row k of `out` is vertex vertices[k]'s posed
/// position, bit for bit what linear_blend_skinning writes in row vertices[k] (the welded
/// positions of a check, skinning::Topology::representative_vertex: the other vertices are not
/// posed at all, nor held).
/// @param out vertices.size() × 3; resized only when its shape differs.
/// @pre every entry of `vertices` is in [0, rest_positions.rows()).
void linear_blend_skinning_rows(
    const Positions& rest_positions,
    const SkinWeights& weights,
    std::span<const BoneTransform> transforms,
    std::span<const std::int32_t> vertices,
    Positions& out);

/// The skinning of one rig, built once: the bone weights with each unweighted vertex given
/// weight 1 on its part's attachment (columns #B … #B + #P − 1), so that one kernel poses every
/// vertex with the transforms of a Pose.
class LinearBlendSkinning {
 public:
  explicit LinearBlendSkinning(const Rig& rig);

  /// #V × (#B + #P) weights.
  [[nodiscard]] const SkinWeights& weights() const { return weights_; }
  /// Writes the #V × 3 positions of the rig's mesh in `pose` into `out` (see linear_blend_skinning).
  /// @pre pose.transforms.size() == #B + #P (as PoseEvaluator makes it).
  void apply(const Pose& pose, Positions& out) const;
  /// apply() for `vertices` only (linear_blend_skinning_rows).
  void apply_rows(const Pose& pose, std::span<const std::int32_t> vertices, Positions& out) const;

 private:
  const Rig* rig_;
  SkinWeights weights_;
};

}  // namespace skelcd::skinning
