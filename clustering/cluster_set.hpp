#pragma once
// The static half of the run-time radial-view method, built once per mesh from a segmentation:
// atomic clusters in welded triangle ids, their observers and bones, the cluster graph with the
// joints between neighbours, one local BVH per atomic cluster and the global BVH whose leaves are
// the local BVHs' roots (paper 002, §6), and which mesh components the radial-view argument may be
// applied to at all (closed, consistently oriented, one part when parts are excluded).

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "culling/bvh.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::clustering {

/// A neighbour of an atomic cluster in the cluster graph.
struct ClusterNeighbour {
  std::int32_t cluster = -1;  ///< the neighbouring atomic cluster
  std::int32_t edge = -1;     ///< index into ClusterSet::joints()
};

/// Where two neighbouring clusters' bones meet (segmentation::ClusterAdjacency), rest pose.
struct ClusterJoint {
  std::int32_t a = -1;
  std::int32_t b = -1;
  /// The bone whose transform carries the joint (the clusters' nearest common ancestor bone,
  /// else the bone of `a`).
  std::int32_t bone = -1;
  Eigen::Vector3d rest = Eigen::Vector3d::Zero();
};

class ClusterSet {
 public:
  /// @param mesh, topology the mesh the method runs on (welded as build_topology welds it).
  /// @param segmentation of the same mesh: one cluster per triangle (Mesh::triangles order).
  /// @param num_bones bones of the rig whose transforms will move the observers.
  /// @param bvh leaf size of the local hierarchies (which keep no binary node volumes: they are
  ///   walked through their wide copy).
  /// @throws InvalidInput naming "clustering" and the offending index when the segmentation does
  ///   not fit the mesh (triangle count, cluster or bone ids out of range, a graph entry between
  ///   unknown clusters).
  ClusterSet(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const segmentation::Segmentation& segmentation,
      std::int32_t num_bones,
      const culling::BvhOptions& bvh = {});

  [[nodiscard]] std::int32_t num_atomic() const {
    return static_cast<std::int32_t>(atomic_bone_.size());
  }
  [[nodiscard]] std::int32_t num_triangles() const {
    return static_cast<std::int32_t>(triangle_atomic_.size());
  }
  /// Atomic cluster of triangle f.
  [[nodiscard]] std::int32_t atomic_of(std::int32_t f) const {
    return triangle_atomic_[static_cast<std::size_t>(f)];
  }
  /// Triangles of atomic cluster a, ascending.
  [[nodiscard]] std::span<const std::int32_t> triangles(std::int32_t a) const {
    const auto i = static_cast<std::size_t>(a);
    return std::span(atomic_triangles_).subspan(
        static_cast<std::size_t>(atomic_offsets_[i]),
        static_cast<std::size_t>(atomic_offsets_[i + 1] - atomic_offsets_[i]));
  }
  [[nodiscard]] std::int32_t bone(std::int32_t a) const {
    return atomic_bone_[static_cast<std::size_t>(a)];
  }
  /// Observer primitive of atomic cluster a (§4.2), rest pose.
  [[nodiscard]] const segmentation::Observer& observer(std::int32_t a) const {
    return atomic_observer_[static_cast<std::size_t>(a)];
  }
  /// Neighbours of atomic cluster a, by ascending cluster id.
  [[nodiscard]] std::span<const ClusterNeighbour> neighbours(std::int32_t a) const {
    const auto i = static_cast<std::size_t>(a);
    return std::span(neighbours_).subspan(
        static_cast<std::size_t>(neighbour_offsets_[i]),
        static_cast<std::size_t>(neighbour_offsets_[i + 1] - neighbour_offsets_[i]));
  }
  [[nodiscard]] std::span<const ClusterJoint> joints() const { return joints_; }

  /// Mesh component (Topology::components) of triangle f, of atomic cluster a.
  [[nodiscard]] std::int32_t component_of_triangle(std::int32_t f) const {
    return triangle_component_[static_cast<std::size_t>(f)];
  }
  [[nodiscard]] std::int32_t component_of_atomic(std::int32_t a) const {
    return atomic_component_[static_cast<std::size_t>(a)];
  }
  [[nodiscard]] std::int32_t num_components() const {
    return static_cast<std::int32_t>(component_ok_.size());
  }
  /// True when the radial-view argument applies to component k: closed (no boundary and no
  /// non-manifold edge), consistently oriented, every atomic cluster touching it lies inside it,
  /// and — when the mesh excludes part pairs — all of it in one part.
  [[nodiscard]] bool component_ok(std::int32_t k) const {
    return component_ok_[static_cast<std::size_t>(k)] != 0;
  }
  /// Component of welded vertex w (that of its incident triangles), −1 when on no triangle.
  [[nodiscard]] std::int32_t component_of_vertex(std::int32_t w) const {
    return vertex_component_[static_cast<std::size_t>(w)];
  }

  /// Local AABB hierarchy of atomic cluster a over its triangles (global triangle ids).
  [[nodiscard]] const culling::AabbBvh& local_bvh(std::int32_t a) const {
    return local_[static_cast<std::size_t>(a)];
  }
  [[nodiscard]] culling::AabbBvh& local_bvh(std::int32_t a) {
    return local_[static_cast<std::size_t>(a)];
  }
  /// The global hierarchy: its "triangles" are the atomic clusters (id a), refit from the roots
  /// of the local hierarchies.
  [[nodiscard]] const culling::AabbBvh& global_bvh() const { return global_; }
  [[nodiscard]] culling::AabbBvh& global_bvh() { return global_; }

 private:
  std::vector<std::int32_t> triangle_atomic_;
  std::vector<std::int32_t> atomic_offsets_, atomic_triangles_;
  std::vector<std::int32_t> atomic_bone_;
  std::vector<segmentation::Observer> atomic_observer_;
  std::vector<std::int32_t> neighbour_offsets_;
  std::vector<ClusterNeighbour> neighbours_;
  std::vector<ClusterJoint> joints_;
  std::vector<std::int32_t> triangle_component_, atomic_component_, vertex_component_;
  std::vector<std::uint8_t> component_ok_;
  std::vector<culling::AabbBvh> local_;
  culling::AabbBvh global_;
};

}  // namespace skelcd::clustering
