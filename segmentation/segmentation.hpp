#pragma once
// The offline segmentation of a rigged mesh (paper 002, §4): weights (bone heat or the rig's own),
// atomic clusters refined against their observers and split into edge-connected pieces, an
// observer primitive per cluster, the cluster graph, and the statistics of paper Table 1.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "segmentation/atomic_clusters.hpp"
#include "segmentation/bone_segment.hpp"
#include "segmentation/cluster_graph.hpp"
#include "segmentation/heat_weights.hpp"
#include "segmentation/observer.hpp"
#include "skinning/mesh.hpp"
#include "skinning/rig.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {

enum class WeightSource : std::uint8_t {
  heat,  ///< bone heat weights computed here (HeatWeightsOptions)
  rig,   ///< the file's own skin weights
};

struct SegmentationOptions {
  WeightSource weights = WeightSource::heat;
  HeatWeightsOptions heat;
  /// θ of the observer test poses (§4.2), degrees, in [0, 90].
  double theta_deg = 10.0;
  /// Refine the clusters against their observers (§4.1); off = the plain largest-weight split
  /// (RVBC's), kept for comparison.
  bool refine = true;
  /// The bones' observer tests and the clusters' run in parallel (oneTBB) on large meshes; the
  /// results are identical. Off: on the calling thread alone (`check --threads 1`).
  bool parallel = true;
};

struct AtomicCluster {
  std::int32_t bone = -1;
  Observer observer;
  /// Positively oriented triangles averaged over the observer test poses, for each candidate.
  double mean_positive_point = 0.0;
  double mean_positive_line = 0.0;
  /// The cluster's triangles, ascending (indices into Mesh::triangles).
  std::vector<std::int32_t> triangles;
};

struct SegmentationStats {
  std::int64_t triangles = 0;
  std::int64_t vertices = 0;         ///< file vertices
  std::int64_t welded_vertices = 0;  ///< after welding seams
  std::int32_t bones = 0;
  std::int32_t atomic_clusters = 0;
  /// Bones that own no cluster (no triangle prefers them, or a bone far from the mesh).
  std::vector<std::int32_t> bones_without_cluster;
  /// Clusters beyond one per non-empty bone: pieces of a bone's triangles that are not
  /// edge-connected became clusters of their own.
  std::int32_t split_clusters = 0;
  std::int32_t point_observers = 0;
  std::int32_t line_observers = 0;
  /// Rest pose, final clusters and observers: negatively oriented and uncertain (exactly zero)
  /// triangles.
  std::int64_t h_minus = 0;
  std::int64_t h_uncertain = 0;
  /// Refinement bookkeeping (with the observers chosen on the initial, per-bone clusters).
  RefinementStats refinement;
  /// Rig weights only: welded vertices with no weight at all, given to their nearest bone.
  std::int64_t unweighted_vertices = 0;
  /// Heat-weight diagnostics (weights == heat only).
  HeatWeightsStats heat;
  /// Wall-clock: the weights (heat solve, or reading the rig's), and the decomposition (initial
  /// assignment, observer choice, refinement, splitting, final observers, graph).
  double weights_s = 0.0;
  double decomposition_ms = 0.0;
};

struct Segmentation {
  /// #F cluster of each triangle (every triangle in exactly one cluster).
  std::vector<std::int32_t> triangle_cluster;
  std::vector<AtomicCluster> clusters;
  std::vector<ClusterAdjacency> graph;
  SegmentationOptions options;
  SegmentationStats stats;
};

/// Segments the welded mesh (V, F) given per-vertex weights.
/// @param V #W × 3 rest positions (welded); @param F #F × 3 welded triangles.
/// @param bones #B rest segments with parents; @param W #W × #B weights (rows sum to 1).
/// @param topology when given and F is its welded_triangles (the very matrix), the face graph
///   starts from its edge lists instead of sorting F's sides again (the same graph).
/// @throws InvalidInput on empty bones or triangles, or shapes that do not match.
[[nodiscard]] Segmentation segment_mesh(
    const skinning::Positions& V,
    const skinning::Triangles& F,
    const std::vector<BoneSegment>& bones,
    const Eigen::MatrixXd& W,
    const SegmentationOptions& options = {},
    const skinning::Topology* topology = nullptr);

/// Segments a rig: welds its mesh, computes or reads its weights, then segment_mesh.
/// @throws InvalidInput naming rig.source: no bones, no triangles, `rig` weights requested but
///   the rig has none (or a vertex without any weight), options out of range.
[[nodiscard]] Segmentation segment(const skinning::Rig& rig, const SegmentationOptions& options = {});

/// The same, with the welded topology of rig.mesh that the caller has already built
/// (`skinning::build_topology(rig.mesh)`, the default weld): a check welds the mesh once for its
/// methods and its segmentation (building it is 5-10 % of a one-sample check on BCN_Epileptic).
/// @throws InvalidInput as above; std::invalid_argument when `topology` does not have the mesh's
///   vertex and triangle counts (it is not the mesh's).
[[nodiscard]] Segmentation segment(
    const skinning::Rig& rig,
    const SegmentationOptions& options,
    const skinning::Topology& topology);

}  // namespace skelcd::segmentation
