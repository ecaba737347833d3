#pragma once
// `normal-cone`: the normal cone test of Volino & Thalmann (DCD; "NCT" in paper 000) and its
// continuous form from ICCD (Tang et al. 2009; "CBC": continuous normal cone plus continuous
// contour test) on the culling module's AABB hierarchy. A node is culled when its surface normal
// cone lies in a half-space and the projection of its whole contour along the cone's axis is a
// simple polygon (every pair of contour edges tested, after 2D box culling); otherwise the standard
// descent follows: both children's self-tests and the pair of children.

#include <cstdint>
#include <memory>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling {

/// Builds the method (what make_method("normal-cone", …) returns).
/// @throws InvalidInput as make_method.
[[nodiscard]] std::unique_ptr<CullingMethod> make_normal_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

/// The same method over the triangles listed in `triangles` only (welded triangle ids): pairs
/// with a triangle outside the list are never reported. Used by routing for the open parts.
/// `features`, when not null, is the mesh's FeatureTopology(mesh, topology), built by the caller
/// (`auto`) and shared rather than built again.
/// @throws InvalidInput as make_method, or for a triangle id out of range.
[[nodiscard]] std::unique_ptr<CullingMethod> make_normal_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles,
    std::shared_ptr<const FeatureTopology> features = {});

}  // namespace skelcd::culling
