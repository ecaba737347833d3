#pragma once
// The relative axis-aligned bounding box filter (paper 002, §6): two triangles that move together
// do not meet, however large their swept boxes. The paper subtracts one common velocity from all
// six vertices and tests the swept boxes of the relative motion. Since 2026-11-30 the filter tests
// instead each triangle's box at t = 0 and at t = 1: two triangles are apart when, on some axis,
// one's box lies strictly below the other's at both ends (grown by the width). For points x(t),
// y(t) of the two, moving linearly, y_k(t) − x_k(t) is linear in t, so positive at both ends it
// is positive in between. That holds in the motion relative to every common velocity at once: it
// removes every pair the relative boxes removed, and more, with no arithmetic but the width's
// (docs/culling.md "Relative boxes at the nodes"). The names stay those of the paper's filter.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// The directions the filter compares on: the three axes. (Nine — the axes and x ± y, y ± z,
/// z ± x — removed a third more of cloth-ball's pairs but cost more to prepare than they saved on
/// the characters: docs/benchmarks.md "Apart at both ends".)
inline constexpr std::size_t kEndDirections = 3;

/// False when, on some axis, the box of triangle a lies more than 2·half_width below that of b, or
/// above it, both at t = 0 and at t = 1 (the header's argument): no point of a then comes within
/// 2·half_width of a point of b at any t in [0,1]. True otherwise, and whenever a coordinate is not
/// finite.
/// @param x_t0,x_t1 #W × 3 welded positions.  @pre half_width >= 0.
[[nodiscard]] bool relative_boxes_overlap(
    const FeatureTopology& topology,
    const TrianglePair& pair,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width);

/// Removes, in place (order kept), the pairs from pairs[first] on without a shared vertex whose
/// relative boxes are apart; pairs sharing a vertex stay (their boxes always meet). Returns the
/// number removed. Allocation-free.
/// @param first pairs before it are kept as they are (a block's pairs filtered as they come).
std::int64_t relative_aabb_filter(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    double half_width,
    std::vector<TrianglePair>& pairs,
    std::size_t first = 0);

/// The same filter with each triangle's boxes at t = 0 and t = 1 computed once per interval
/// (prepare), so that a pair costs two records instead of twelve corner lookups. Every bound is an
/// input double (min and max are exact); with width the gap must exceed 2·half_width with the sum
/// rounded up. Tested against relative_boxes_overlap and exact arithmetic
/// (tests/culling/test_cluster_checks.cpp).
class RelativeAabbFilter {
 public:
  /// Per-triangle boxes at the two ends of the interval x_t0 → x_t1 (#W × 3 each).
  /// Allocation-free once sized for the topology.
  void prepare(
      const FeatureTopology& topology,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1);
  /// relative_boxes_overlap for the prepared interval (the same guarantee).
  [[nodiscard]] bool overlap(const TrianglePair& pair, double half_width) const;
  /// relative_aabb_filter for the prepared interval: removes, in place (order kept), the pairs from
  /// pairs[first] on without a shared vertex whose relative boxes are apart; returns how many.
  std::int64_t filter(
      const FeatureTopology& topology,
      double half_width,
      std::vector<TrianglePair>& pairs,
      std::size_t first = 0) const;

 private:
  /// A triangle's box at t = 0 and at t = 1 (96 bytes).
  struct Triangle {
    double lo0[kEndDirections], hi0[kEndDirections], lo1[kEndDirections], hi1[kEndDirections];
  };
  std::vector<Triangle> triangles_;
};

/// How far an interval moves its vertices against the size of its triangles: the mean over the
/// vertices of their largest coordinate displacement, over the mean over the triangles of the
/// longest side of their box at t = 0 (0 when either mean is 0 or not finite). The hierarchy
/// methods test node pairs in the relative motion as well (Bvh::refit_end_boxes) from
/// kNodeRelativeMotion on: below it the swept boxes are barely larger than the still ones and
/// the relative test cannot prune what the swept one keeps (docs/culling.md "Relative boxes at
/// the nodes"). O(#W + #F).
/// @param x_t0,x_t1 #W × 3 welded positions.
[[nodiscard]] double motion_scale(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1);

/// The motion_scale from which node pairs are tested in the relative motion too.
inline constexpr double kNodeRelativeMotion = 0.4;

/// A CCD query's triangle pairs through the relative AABB filter when that pays (`kdop`,
/// docs/culling.md "Relative boxes in `kdop`"): the filter costs about as much per pair as a few
/// percent of what a kept pair costs in the feature and elementary stages, and removes from none (a
/// body at rest, a slow garment) to most of the pairs (a character with root motion, a falling
/// cloth: what moves together). Each query starts with a trial on its first pairs, filtered one by
/// one from the positions (relative_boxes_overlap: nothing held); once the trial has seen its
/// pairs, the filter is kept for the rest of the query when it removed at least kTrialShare of
/// them (the per-triangle boxes are then prepared: RelativeAabbFilter), else no later pair is
/// filtered. The trial is the query's first trial_pairs pairs in traversal order, which
/// installments do not change, so the decision and every counter are the same for any block size.
/// Either way the contacts are the same: a pair the filter removes has none.
class RelativePairTrial {
 public:
  /// The share of the trial's pairs the filter must remove to be kept for the query.
  static constexpr double kTrialShare = 0.25;
  /// The longest trial, in pairs.
  static constexpr std::size_t kMaxTrial = std::size_t{1} << 15;
  /// Pairs of the trial: the query's first min(#triangles, kMaxTrial) pairs (at least 1).
  [[nodiscard]] static std::size_t trial_pairs(std::int32_t num_triangles);

  /// Starts a query whose trial is its first `trial` pairs (≥ 1).
  void start(std::size_t trial);
  /// Filters pairs[first..] as the query stands (trial, kept, dropped); returns how many it
  /// removed. Decides at the end of the trial. Allocation-free but for the first prepare of a
  /// topology.
  std::int64_t filter(
      const FeatureTopology& topology,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      double half_width,
      std::vector<TrianglePair>& pairs,
      std::size_t first);
  /// True once the trial has kept the filter for this query.
  [[nodiscard]] bool kept() const { return state_ == State::kept; }
  /// True while the query is still in its trial.
  [[nodiscard]] bool in_trial() const { return state_ == State::trial; }

 private:
  enum class State : std::uint8_t { trial, kept, dropped };
  RelativeAabbFilter prepared_;
  std::size_t trial_ = 1;
  std::int64_t seen_ = 0;
  std::int64_t removed_ = 0;
  State state_ = State::dropped;
};

}  // namespace skelcd::culling
