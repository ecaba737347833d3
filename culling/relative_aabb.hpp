#pragma once
// The relative axis-aligned bounding box filter (paper 002, §6): two triangles that move together
// do not meet, however large their swept boxes. Subtracting one common velocity from all six
// vertices changes no distance between points of the two triangles at any instant, so if the swept
// boxes of the *relative* motion are apart, the triangles are apart over the whole interval. The
// common velocity is the mean of the six (any vector would be sound; the mean makes the boxes
// small). Rounding is outward: each relative end position is bracketed by the doubles around it
// (with a width; without one, monotone rounding is enough: RelativeAabbFilter).

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// True when the swept AABBs of triangles a and b, in the motion relative to the mean velocity of
/// their six corners and grown by `half_width` each, overlap. False proves that no point of a comes
/// within 2·half_width of a point of b at any t in [0,1].
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

/// The same filter with what each triangle contributes computed once per interval (prepare):
/// its corners' box at t = 0, at t = 1, and a sixth of the sum of its corners' displacements, so
/// that a pair costs two box translations instead of twelve corner lookups. The relative box of a
/// triangle is [min(lo₀, ↓(lo₁ − w)), max(hi₀, ↑(hi₁ − w))] per axis: the rounded min of the
/// corners' x₁ − w is the rounded (min x₁) − w (rounding is monotone), bracketed outwards as above;
/// w, the mean of the six displacements, is the sum of the two triangles' sixths (another rounding
/// of the mean: any common vector is sound). Without width (`half_width` 0, as the radial-view
/// methods run) no end is bracketed: the boxes are apart only when a rounded end lies strictly
/// beyond another, and since each end is an input double or fl(y − w) with the pair's one w,
/// monotone rounding makes the exact ends lie so too. Tested against relative_boxes_overlap and
/// exact arithmetic (tests/culling/test_cluster_checks.cpp).
class RelativeAabbFilter {
 public:
  /// Per-triangle boxes and displacements of the interval x_t0 → x_t1 (#W × 3 each).
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
  struct Triangle {
    std::array<double, 3> lo0, hi0, lo1, hi1, sixth_displacement;
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
