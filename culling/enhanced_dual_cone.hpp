#pragma once
// `enhanced-dual-cone` (paper 000, Wang, Tang, Wang & Tong 2018): self-collision culling for
// meshes with open boundaries that misses nothing. Each hierarchy node with grandchildren is
// tested with the three conditions of §5.1 — its surface normal cone lies in a half-space; each
// chain of its contour, split by the four sub-surfaces, has a binormal cone of half-angle < π/2 in
// the projection plane (so the chain is simple); the chains' projections do not meet — and a
// node that fails descends straight to its four sub-surfaces and their six pairs (Algorithm 3).
// DCD uses the static normals and the contour at the instant; CCD the continuous normal cone
// (Bernstein control vectors of n(t)) and the continuous contour test.
// docs/dual-cone.md says where and why this differs from the paper's text.

#include <cstdint>
#include <memory>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling {

/// Builds the method (what make_method("enhanced-dual-cone", …) returns).
/// @throws InvalidInput as make_method.
[[nodiscard]] std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

/// The same method over the triangles listed in `triangles` only (welded triangle ids): pairs
/// with a triangle outside the list are never reported. Used by routing for the open parts.
/// @throws InvalidInput as make_method, or for a triangle id out of range.
[[nodiscard]] std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles);

}  // namespace skelcd::culling
