#pragma once
// What the cone culling methods (`normal-cone`, `dual-cone`, `enhanced-dual-cone`) report beside
// the shared Counters: how many hierarchy nodes their cone tests examined, culled, and why the
// others failed. Read it through `method.cone_statistics()` (null for other methods).

#include <array>
#include <cstdint>

#include "culling/contour.hpp"

namespace skelcd::culling {

/// Cone-test statistics of the last detect_dcd / detect_ccd call.
struct ConeCullingStats {
  std::int64_t nodes_tested = 0;        ///< node self-tests evaluated with the cone criteria
  std::int64_t nodes_culled = 0;        ///< ... that proved the node free of self-collision
  std::int64_t failed_normal_cone = 0;  ///< condition 1: SNC not within a half-space
  /// Condition 1 proven triangle by triangle (around the mean normal) after the node's
  /// hierarchical cone failed — counted among the nodes that passed condition 1.
  std::int64_t normal_direct_passes = 0;
  std::int64_t failed_topology = 0;  ///< the node's contour is not one simple loop
  /// Condition 2: FASTCD's BNC test failed; for enhanced-dual-cone, a chain failed the dual-cone
  /// test (and was cut into monotone runs) and condition 3 then failed as well.
  std::int64_t failed_dual_cone = 0;
  std::int64_t failed_contour = 0;  ///< condition 3: projected contour edges may meet
  /// Algorithm 3's ten results, as failures counted over the nodes whose condition 1 held:
  /// [0..3] the sub-surface tests R_ll, R_lr, R_rl, R_rr (a chain failed the dual-cone test);
  /// [4..9] the pair tests (ll,lr), (ll,rl), (ll,rr), (lr,rl), (lr,rr), (rl,rr) (only the first
  /// failing pair of a node: the test stops there).
  std::array<std::int64_t, 10> ten_results_failed{};
  std::int64_t subtree_pairs = 0;  ///< node-pair traversals started (Collide of Algorithm 3)
  ContourTestCounters contour;
  /// True when cone culling was off for this call (min_separation > 0: the cone theorems are
  /// about intersection, not distance — the method then equals `bvh`).
  bool culling_disabled = false;
};

/// Implemented by the cone methods beside CullingMethod; CullingMethod::cone_statistics() returns
/// it (null for other methods).
class ConeStatistics {
 public:
  virtual ~ConeStatistics() = default;
  [[nodiscard]] virtual const ConeCullingStats& cone_stats() const = 0;
  /// Static contour statistics of the method's hierarchy (nodes per ContourStatus).
  [[nodiscard]] virtual const NodeContours& contours() const = 0;
};

/// Index into ConeCullingStats::ten_results_failed of the pair test (p, q), p < q < 4.
[[nodiscard]] constexpr int ten_result_pair_index(int p, int q) {
  // (0,1)→4 (0,2)→5 (0,3)→6 (1,2)→7 (1,3)→8 (2,3)→9
  return p == 0 ? 3 + q : (p == 1 ? 5 + q : 9);
}

}  // namespace skelcd::culling
