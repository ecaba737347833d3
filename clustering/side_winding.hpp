#pragma once
// The generalized winding number on the front side of a triangle of a closed oriented surface,
// exact (docs/radial-view.md, "The local guard"). Radial view's local guard skips a pair of
// same-class triangles only where their patches — connected sets of triangles no intersection
// cuts — have the same winding number in front; one ray per patch decides it.

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
/// O(|surface|) per call.
[[nodiscard]] std::optional<int> front_winding(
    std::span<const std::int32_t> surface,
    const culling::Aabb& box,
    const skinning::Triangles& triangles,
    const skinning::Positions& x,
    std::int32_t f,
    int attempt);

}  // namespace skelcd::clustering
