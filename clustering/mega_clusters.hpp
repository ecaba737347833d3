#pragma once
// Per interval: the orientation class of every triangle against its cluster's observer, with the
// clusters either fixed (`rvbc`, Wong et al. 2013: each atomic cluster on its own) or merged into
// mega clusters (`dynamic`, paper 002 §5): reset every interval; a seed atomic cluster drawn by a
// seeded random generator grows over adjacent atomic clusters while the merging cost
//   D = (|H⁻(C̃ᴬ, o(Cᴹ))| + |Hᵘ(C̃ᴬ, o(Cᴹ))|) / |C̃ᴬ|
// stays below γ; the observer of a mega cluster becomes the joint of the first two atomic
// clusters' bones and stays there; repeat until every atomic cluster is placed. The triangles that
// were not positive in the previous interval are classified first, so a merge that will fail
// stops early (§5, implementation details).

#include <cstdint>
#include <span>
#include <vector>

#include "clustering/cluster_set.hpp"
#include "clustering/orientation_class.hpp"
#include "segmentation/observer.hpp"
#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"

namespace skelcd::clustering {

/// An observer over one interval: a moving point, or a moving segment (line observer).
struct MovingObserver {
  segmentation::ObserverKind kind = segmentation::ObserverKind::point;
  MovingPoint point;      ///< kind == point
  MovingSegment segment;  ///< kind == line
};

/// The observers of one interval, posed by the bone transforms at its two ends.
struct IntervalObservers {
  std::vector<MovingObserver> atomic;  ///< #atomic clusters: each one's own primitive
  std::vector<MovingPoint> joints;     ///< #ClusterSet::joints(): the joint of each neighbour pair
};

/// Poses the rest observers and joints of `clusters` with the bone transforms at t0 and t1.
/// @param t0,t1 at least one transform per bone (Pose::transforms).
/// @throws InvalidInput when a transform list is shorter than the bones the clusters use.
void pose_observers(
    const ClusterSet& clusters,
    std::span<const skinning::BoneTransform> t0,
    std::span<const skinning::BoneTransform> t1,
    IntervalObservers& out);

struct MegaClusterOptions {
  /// false: `rvbc` (every atomic cluster is its own mega cluster, with its own observer).
  bool merge = true;
  /// Merge threshold γ on D (§5); a cluster joins when D < γ.
  double gamma = 0.05;
  /// Seed of the generator that draws the seed clusters; the same seed gives the same clusters.
  std::uint64_t seed = 1;
};

/// What one interval's classification produced.
struct IntervalClasses {
  /// #F class of each triangle against its mega cluster's observer.
  std::vector<OrientationClass> triangle_class;
  /// #atomic: mega cluster of each atomic cluster.
  std::vector<std::int32_t> atomic_mega;
  /// #mega: the observer each mega cluster's triangles were classified against, and its
  /// members (atomic ids; the seed first, then in the order they joined).
  std::vector<MovingObserver> mega_observer;
  std::vector<std::int32_t> mega_offsets;  ///< #mega + 1, CSR into mega_members
  std::vector<std::int32_t> mega_members;
  std::int64_t h_minus = 0;
  std::int64_t h_uncertain = 0;
  /// Classifications made (merge attempts included) and merge attempts (accepted or not).
  std::int64_t classifications = 0;
  std::int64_t merge_attempts = 0;
  /// Microseconds classifying triangles, and in the merging logic around it.
  double classify_us = 0.0;
  double merge_us = 0.0;

  [[nodiscard]] std::int32_t num_mega() const {
    return static_cast<std::int32_t>(mega_observer.size());
  }
  [[nodiscard]] std::span<const std::int32_t> members(std::int32_t m) const {
    const auto i = static_cast<std::size_t>(m);
    return std::span(mega_members).subspan(
        static_cast<std::size_t>(mega_offsets[i]),
        static_cast<std::size_t>(mega_offsets[i + 1] - mega_offsets[i]));
  }
};

/// Builds the classes of each interval; keeps what the next interval re-uses (the non-positive
/// triangles of every atomic cluster) and its scratch.
class MegaClusterBuilder {
 public:
  MegaClusterBuilder(const ClusterSet& clusters, const MegaClusterOptions& options);

  /// Classifies every triangle for the interval x_t0 → x_t1 and forms the mega clusters.
  /// @param triangles #F × 3 welded triangles; @param x_t0,x_t1 #W × 3 welded positions.
  void build(
      const skinning::Triangles& triangles,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      const IntervalObservers& observers,
      IntervalClasses& out);

  [[nodiscard]] const MegaClusterOptions& options() const { return options_; }

 private:
  /// Classifies the triangles of atomic cluster a against `observer` into out.triangle_class,
  /// those of `first` first, then last interval's non-positive ones; stops as soon as the
  /// non-positive count reaches `limit` (then returns false). Returns true when it stays below
  /// the limit. The outcome does not depend on the order; the work does. The non-positive
  /// triangles it met are left in found_.
  bool evaluate(
      std::int32_t a,
      const MovingObserver& observer,
      std::int64_t limit,
      IntervalClasses& out,
      std::span<const std::int32_t> first = {});
  /// evaluate() against joint e (ClusterSet::joints), its outcome kept for the next interval.
  bool evaluate_at_joint(
      std::int32_t a,
      std::int32_t e,
      const MovingObserver& joint,
      std::int64_t limit,
      IntervalClasses& out);
  /// The slot of a's kept outcome against joint e (e one of the joints a meets a neighbour at),
  /// else −1.
  [[nodiscard]] std::int32_t joint_slot(std::int32_t a, std::int32_t e) const;
  void remember_non_positive(IntervalClasses& out);

  const ClusterSet& clusters_;
  MegaClusterOptions options_;
  const skinning::Triangles* triangles_ = nullptr;
  const skinning::Positions* x_t0_ = nullptr;
  const skinning::Positions* x_t1_ = nullptr;
  // Last interval's non-positive triangles per atomic cluster (CSR), and per-triangle stamps that
  // mark what an evaluation already classified.
  std::vector<std::int32_t> previous_offsets_, previous_;
  std::vector<std::int32_t> next_offsets_, next_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t evaluation_ = 0;
  // Merging scratch.
  std::vector<std::int32_t> unplaced_, unplaced_slot_, queue_;
  std::vector<std::uint32_t> tried_by_;
  std::uint32_t mega_stamp_ = 0;
  // Per atomic cluster, the joints it meets its neighbours at (CSR) and whether its last
  // evaluation at each failed, kept over the intervals: a merge of two clusters needs both to
  // pass, and the one that failed last time is classified first (the merge's outcome is the same
  // in either order, only the classifications it takes differ).
  std::vector<std::int32_t> joint_offsets_, joint_ids_;
  std::vector<std::uint8_t> joint_failed_;
  std::vector<std::vector<std::int32_t>> joint_failures_;  // per slot: what its last failure met
  std::vector<std::int32_t> found_;                        // evaluate's non-positive triangles
  std::vector<std::int32_t> seed_failed_;  // joints the current seed failed at in this interval
};

/// The limit on non-positive triangles for an atomic cluster of `size` triangles: D < γ holds
/// exactly when the count stays below it (the smallest integer n with n ≥ γ·size).
[[nodiscard]] std::int64_t merge_limit(std::int64_t size, double gamma);

}  // namespace skelcd::clustering
