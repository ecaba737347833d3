#pragma once
// The cluster graph: which atomic clusters share edges, and the joint at which their bones meet
// (what the run-time merging of §5 needs: neighbours, and the observer point of a merged pair).

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "segmentation/bone_segment.hpp"
#include "segmentation/face_graph.hpp"

namespace skelcd::segmentation {

struct ClusterAdjacency {
  std::int32_t a = -1;  ///< cluster id, a < b
  std::int32_t b = -1;
  /// Mesh edges with triangles of both clusters on them.
  std::int32_t shared_edges = 0;
  /// Nearest common ancestor of the two clusters' bones (the bone itself when both pieces belong
  /// to one bone or one bone is the other's ancestor), −1 when they are in different trees.
  std::int32_t ancestor_bone = -1;
  /// The joint where the bones meet, rest pose, object space:
  ///  - same bone: its midpoint;
  ///  - one bone an ancestor of the other: the head of the bone that leaves the ancestor towards
  ///    the other (for parent and child, the child's head);
  ///  - otherwise: the midpoint of the heads of the two bones that leave the common ancestor
  ///    towards each (for siblings, their shared joint), or of the two roots' heads when there
  ///    is no common ancestor.
  Eigen::Vector3d joint = Eigen::Vector3d::Zero();
};

/// Where two bones meet: their nearest common ancestor and the joint (see ClusterAdjacency).
struct BoneJoint {
  std::int32_t ancestor_bone = -1;
  Eigen::Vector3d joint = Eigen::Vector3d::Zero();
};

/// The joint between bones j and k and their nearest common ancestor (see ClusterAdjacency).
/// @param bones rest segments with parents (parents may come in any order but form a forest).
[[nodiscard]] BoneJoint bone_joint(
    const std::vector<BoneSegment>& bones,
    std::int32_t j,
    std::int32_t k);

/// Every pair of clusters sharing at least one mesh edge, sorted by (a, b).
/// @param triangle_cluster #F; @param cluster_bone #C.
[[nodiscard]] std::vector<ClusterAdjacency> cluster_graph(
    const FaceGraph& graph,
    std::span<const std::int32_t> triangle_cluster,
    std::span<const std::int32_t> cluster_bone,
    const std::vector<BoneSegment>& bones);

}  // namespace skelcd::segmentation
