#pragma once
// The culling method interface (a run-time choice, DESIGN.md "Methods"): a method is built once for
// a mesh's topology and then answers, per instant (DCD) or per interval (CCD), which primitive pairs
// collide — through the shared elementary tests of ccd/ at the requested accuracy.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "culling/bvh.hpp"
#include "culling/elementary.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

class MethodExtension;

struct MethodOptions {
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  /// Contact distance (coordinate units); 0 = touching counts. CCD bounds are inflated by half of
  /// it each, so features within this distance always reach the elementary test.
  double min_separation = 0.0;
  /// Hierarchy build options of the hierarchy methods (`bvh`, `kdop`).
  BvhOptions bvh{};
  /// The elementary tests to call; null members mean the ccd/ kernels.
  ElementaryTests elementary{};
  /// Methods built above culling/ (culling/method_extension.hpp): make_method builds its names too.
  std::shared_ptr<const MethodExtension> extension{};
};

class CullingMethod {
 public:
  virtual ~CullingMethod() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;

  /// Intersecting triangle pairs at one instant: every pair of distinct triangles with a common
  /// point beyond the vertices or edge they share (exact), except part-excluded pairs and
  /// duplicate faces on the same three vertices.
  /// @param x #W × 3 welded positions (finite: the runner checks).
  /// @param out cleared by the caller; filled with dcd_pairs, counters and times.
  /// @throws InvalidInput when x does not have #W rows.
  /// @note Allocation-free after the first calls, except when `out` or the method's candidate
  ///       buffers must grow beyond what an earlier call needed.
  virtual void detect_dcd(const skinning::Positions& x, FrameResult& out) = 0;

  /// VF and EE contacts over the interval with linear motion from x_t0 to x_t1: every vertex-face
  /// and edge-edge pair not sharing a vertex (and not part-excluded) that the elementary test
  /// reports, each tested once.
  /// @param x_t0,x_t1 #W × 3 welded positions at the interval's ends.
  /// @param out cleared by the caller; filled with contacts, counters and times.
  /// @throws InvalidInput when x_t0 or x_t1 does not have #W rows.
  virtual void detect_ccd(
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      FrameResult& out) = 0;
};

/// Names of the methods available now, in the order `bench` lists them.
[[nodiscard]] std::vector<std::string> method_names();

/// Builds method `name` for `mesh` / `topology` (the method copies what it needs).
/// Methods: `brute` (every feature pair, volume-filtered: the reference on small meshes), `bvh`
/// (AABB hierarchy), `kdop` (16-DOP hierarchy). All report identical contacts with the `exact`
/// accuracy; docs/culling.md says what may differ with `conservative` (false positives only).
/// @throws InvalidInput for an unknown name (the message lists the known ones), a mesh and
///         topology that disagree, a negative or non-finite min_separation, or min_separation > 0
///         with the `exact` accuracy.
[[nodiscard]] std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

}  // namespace skelcd::culling
