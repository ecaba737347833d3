#pragma once
// Atomic clusters (paper 002, §4.1): every triangle goes to the bone of its largest weight; the
// clusters are then refined against their observers — non-positively oriented triangles leave,
// clusters grow back over the triangles that are positively oriented to them, and finally grow
// without that constraint so that every triangle belongs to a cluster — and split into
// edge-connected pieces.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "segmentation/face_graph.hpp"
#include "segmentation/observer.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::segmentation {

/// For each triangle, the bone with the largest weight summed over its three corners (ties: the
/// lower bone index).
/// @param W #W × #B weights; @param F #F × 3 indices into W's rows.  @return #F bone ids.
[[nodiscard]] std::vector<std::int32_t> largest_weight_bones(
    const Eigen::MatrixXd& W,
    const skinning::Triangles& F);

struct RefinementStats {
  /// Non-positively oriented triangles (negative or uncertain to their label's observer, rest
  /// pose) before and after refinement; after <= before always.
  std::int64_t non_positive_before = 0;
  std::int64_t non_positive_after = 0;
  /// Triangles removed from their cluster, taken back by a cluster to which they are positively
  /// oriented, and assigned without that constraint.
  std::int64_t removed = 0;
  std::int64_t regrown_positive = 0;
  std::int64_t regrown_unconstrained = 0;
  /// Removed triangles in a component where every triangle was removed: no cluster could grow
  /// into them, so they went back to their first label.
  std::int64_t restored = 0;
};

/// Refines `labels` in place (§4.1), with the observer of label l being observers[l]:
///  1. remove every triangle that is not positively oriented to its label's observer;
///  2. grow: a removed triangle next to a labelled one joins a neighbouring label whose observer
///     it is positively oriented to (repeated while any triangle joins);
///  3. grow one ring without the constraint, then 2 again, until every triangle is labelled.
/// Growth runs in synchronous rounds (decisions read the labels as they were at the start of the
/// round), and among several candidate labels the triangle takes the one with the largest summed
/// corner weight (ties: lowest label), so the result does not depend on traversal order.
/// @param V #W × 3 rest positions; @param F #F × 3; @param graph face_graph(F).
/// @param observers one per label; @param W #W × #labels weights (the affinity of a triangle to
///   a label). @param labels #F, each in [0, observers.size()).
[[nodiscard]] RefinementStats refine_labels(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    const FaceGraph& graph,
    std::span<const Observer> observers,
    const Eigen::MatrixXd& W,
    std::vector<std::int32_t>& labels);

struct ConnectedClusters {
  /// #F cluster of each triangle.
  std::vector<std::int32_t> triangle_cluster;
  /// #C label of each cluster. Clusters are numbered by (label, smallest triangle id).
  std::vector<std::int32_t> cluster_label;
};

/// Splits each label into its edge-connected pieces: one cluster per piece.
[[nodiscard]] ConnectedClusters split_connected(
    const FaceGraph& graph,
    std::span<const std::int32_t> labels);

}  // namespace skelcd::segmentation
