#pragma once
// The generalized winding number on the front side of a triangle of a closed oriented surface,
// exact (docs/radial-view.md, "The local guard"). Radial view's local guard skips a pair of
// same-class triangles only where their patches — connected sets of triangles no intersection
// cuts — have the same winding number in front; one ray per patch decides it.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>

#include "culling/dop.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::clustering {

/// The box of the corners of `surface` (ids into `triangles`) at positions x: front_winding's
/// rays end beyond it. Computed once per surface and instant, for all its rays.
[[nodiscard]] culling::Aabb surface_box(
    std::span<const std::int32_t> surface,
    const skinning::Triangles& triangles,
    const skinning::Positions& x);

/// The winding number w of the closed, consistently oriented surface `surface` (ids into
/// `triangles`, f among them; `box` its surface_box) just in front of triangle f — on the side its
/// normal (b − a) × (c − a) points to, near its centroid. w is 0 far away and drops by one across a
/// triangle along its normal (an outward-oriented embedded surface: 1 inside, 0 outside).
///
/// Exact, or nothing: a short segment through f near its centroid, along its normal, must cross
/// f properly and meet no other triangle of the surface; then w at the segment's front end is
/// counted along a ray to a point beyond the surface's box (+1 for each crossing along a normal,
/// −1 against one), every crossing decided by exact orientations. nullopt when this attempt cannot
/// decide: f is degenerate, the segment meets another triangle, or the ray touches an edge or a
/// vertex of some triangle or runs in its plane. Attempts 0, 1, … tilt the ray differently.
/// O(|surface|) per call; winding_ray + count_winding do the same over fewer triangles.
[[nodiscard]] std::optional<int> front_winding(
    std::span<const std::int32_t> surface,
    const culling::Aabb& box,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f,
    int attempt);

/// front_winding's two segments for triangle f and `attempt`: the short one [back, front] through
/// f along its normal, then the ray [front, far] to beyond `box`. nullopt when f is degenerate,
/// the short segment does not cross f properly, or the ray's end is not outside the box.
struct WindingRay {
  Eigen::Vector3d back, front, far;
  Eigen::Vector3d dir;  ///< unit direction of [front, far]
};
[[nodiscard]] std::optional<WindingRay> winding_ray(
    const culling::Aabb& box,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f,
    int attempt);

/// front_winding's count along `ray` (from winding_ray for f) over the triangles `candidates`
/// (ids into `triangles`; f may be among them or not). Equals front_winding over a surface when
/// `candidates` holds every triangle of it that may meet either segment — a triangle left out
/// must lie in a box that segment_meets_box says neither segment meets.
[[nodiscard]] std::optional<int> count_winding(
    const WindingRay& ray,
    std::span<const std::int32_t> candidates,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f);

/// False only when the segment [p, q] certainly misses `box` (a slab test with margins well above
/// its rounding): every point of a box it returns false for is off the segment. Used to gather
/// count_winding's candidates from a hierarchy.
[[nodiscard]] bool segment_meets_box(
    const Eigen::Vector3d& p, const Eigen::Vector3d& q, const culling::Aabb& box);

}  // namespace skelcd::clustering
