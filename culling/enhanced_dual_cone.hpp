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

/// Variants of the method (for routing, benchmarks and the traversal-scheme comparison).
struct EnhancedDualConeOptions {
  /// Algorithm 3's scheme: a node that is not culled descends straight to its sub-surfaces'
  /// self-tests and their six pairs. false: the simple top-down scheme (both children's
  /// self-tests and their pair), which tests the children with the cone criteria too.
  bool grandchildren_descent = true;
  /// When not empty, the only triangles covered (welded triangle ids): pairs with a triangle
  /// outside the list are never reported. Routing uses it for the open components.
  std::vector<std::int32_t> triangles;
  /// When not null, the mesh's FeatureTopology(mesh, topology), built by the caller (`auto`) and
  /// shared rather than built again (docs/culling.md "Bounded memory").
  std::shared_ptr<const FeatureTopology> features{};
};

/// The method with explicit variant options.
/// @throws InvalidInput as make_method, or for a triangle id out of range.
[[nodiscard]] std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const EnhancedDualConeOptions& variant);

}  // namespace skelcd::culling
