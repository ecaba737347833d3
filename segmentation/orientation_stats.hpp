#pragma once
// How many triangles are not positively oriented to their cluster's observer: in the rest pose
// (exact sign) and per interval of a clip (the continuous classes of §3.1, decided by the
// conservative cubic-sign classifier of ccd/) — the |H⁻| and |Hᵘ| columns of paper Table 1.

#include <cstdint>
#include <span>
#include <string>

#include "segmentation/segmentation.hpp"
#include "skinning/motion.hpp"
#include "skinning/pose.hpp"

namespace skelcd::segmentation {

struct OrientationCounts {
  std::int64_t h_plus = 0;
  std::int64_t h_minus = 0;
  std::int64_t h_uncertain = 0;
};

/// Counts at one instant: each triangle against its cluster's observer, the bone moved by
/// `transforms[bone]` (object-space rest → posed; pass the identity for the rest pose).
/// @param x #W × 3 welded positions at that instant; @param F #F × 3 welded triangles.
/// @param transforms at least #B bone transforms (Pose::transforms).
[[nodiscard]] OrientationCounts count_orientations(
    const Segmentation& segmentation,
    const skinning::Positions& x,
    const skinning::Triangles& F,
    std::span<const skinning::BoneTransform> transforms);

/// Counts over one interval: H⁺ when (p(t) − q(t)) · n(t) > 0 on all of [0, 1] is proven, H⁻ when
/// < 0 is proven, Hᵘ otherwise (vertices and observer moving linearly between the two samples).
/// A line observer views each triangle from a fixed point of the bone segment over the interval:
/// corner a's clamped projection parameter at t0, moving with the bone.
[[nodiscard]] OrientationCounts count_orientations_interval(
    const Segmentation& segmentation,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const skinning::Triangles& F,
    std::span<const skinning::BoneTransform> transforms_t0,
    std::span<const skinning::BoneTransform> transforms_t1);

struct ClipOrientationStats {
  std::string clip;
  std::int32_t intervals = 0;
  /// Averages and maxima over the intervals.
  double mean_h_minus = 0.0;
  double mean_h_uncertain = 0.0;
  std::int64_t max_h_minus = 0;
  std::int64_t max_h_uncertain = 0;
  double seconds = 0.0;
};

/// Classifies every interval of `motion` (its samples i, i+1; bone poses from
/// Motion::bone_transforms) against the segmentation of its rig; the mesh is welded as segment()
/// welds it.
/// @throws InvalidInput when the motion has no skeleton or the segmentation does not fit it
/// (triangle or bone count).
[[nodiscard]] ClipOrientationStats clip_orientation_stats(
    const Segmentation& segmentation, const skinning::Motion& motion);

}  // namespace skelcd::segmentation
