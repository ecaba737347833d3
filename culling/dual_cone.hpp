#pragma once
// `dual-cone`: the BVH-based dual-cone culling of FASTCD (Heo et al. 2010) as paper 000 §4
// describes it — kept to *show* its false negatives. Each node has a surface normal cone (SNC)
// and a binormal cone (BNC) of the binormals n × e of the mesh's own boundary edges in it (the
// internal boundary edges the hierarchy creates are ignored); a node is culled when θ_n < π/2 and
// either it holds no boundary edge or |A_n · A_b| < cos θ_b (the Dual-Cone Theorem). For CCD the
// cones bound the Bernstein control vectors of n(t) and of n(t) × e(t).
// May miss collisions by design: never use it where a miss matters.

#include <cstdint>
#include <memory>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling {

/// Builds the method (what make_method("dual-cone", …) returns).
/// @throws InvalidInput as make_method.
[[nodiscard]] std::unique_ptr<CullingMethod> make_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

/// The same method over the triangles listed in `triangles` only (welded triangle ids): pairs
/// with a triangle outside the list are never reported. Used by routing for the open parts.
/// `features`, when not null, is the mesh's FeatureTopology(mesh, topology), built by the caller
/// (`auto`) and shared rather than built again.
/// @throws InvalidInput as make_method, or for a triangle id out of range.
[[nodiscard]] std::unique_ptr<CullingMethod> make_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles,
    std::shared_ptr<const FeatureTopology> features = {});

}  // namespace skelcd::culling
