#pragma once
// A bounding volume hierarchy over triangles, built once top-down and refit bottom-up every
// interval. Flat layout: nodes in depth-first order, a node's left child right after it, its
// triangles one contiguous range of triangle_order().

#include <cstdint>
#include <span>
#include <vector>

#include "culling/dop.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

struct BvhOptions {
  /// Most triangles in a leaf (>= 1). Larger leaves: fewer nodes to refit and visit, more
  /// triangle-box tests inside leaf pairs (bench/culling measures the trade).
  int leaf_size = 1;
};

struct BvhNode {
  std::int32_t begin = 0;  ///< first slot of the node's triangles in Bvh::triangle_order()
  std::int32_t end = 0;    ///< one past the last slot
  std::int32_t right = 0;  ///< index of the right child; 0 for a leaf (the left child is index + 1)
  [[nodiscard]] bool is_leaf() const { return right == 0; }
  [[nodiscard]] std::int32_t size() const { return end - begin; }
};

/// Hierarchy of Dop<N> volumes (Dop<3>: AABB, Dop<8>: 16-DOP) over a set of triangles.
template <int N>
class Bvh {
 public:
  using Volume = Dop<N>;

  Bvh() = default;

  /// Builds over every triangle: median split (by count) along the longest axis of the
  /// triangles' centroids, recursively, until a range holds at most leaf_size triangles.
  /// @param triangles #F × 3 vertex ids into positions.
  /// @param positions #W × 3 positions the split is computed from (rest pose, usually).
  /// @throws InvalidInput when leaf_size < 1 or a vertex id is out of range (naming the triangle).
  Bvh(const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      const BvhOptions& options = {});

  /// Builds over the triangles listed in `subset` (ids into `triangles`; a cluster, a part).
  /// @throws InvalidInput as above, or for a subset id out of range.
  Bvh(const skinning::Triangles& triangles,
      const skinning::Positions& positions,
      std::span<const std::int32_t> subset,
      const BvhOptions& options = {});

  /// Bottom-up refit: a leaf's volume is the union of its triangles' volumes, a parent's the
  /// union of its children's. Unions are exact (min/max), so every node contains its triangles'
  /// volumes exactly as given. Allocation-free.
  /// @param triangle_bounds indexed by triangle id (#F of the `triangles` built from).
  void refit(std::span<const Volume> triangle_bounds);

  [[nodiscard]] std::span<const BvhNode> nodes() const { return nodes_; }
  [[nodiscard]] std::span<const Volume> node_bounds() const { return node_bounds_; }
  /// Triangle ids in leaf order; node n holds triangle_order()[n.begin .. n.end).
  [[nodiscard]] std::span<const std::int32_t> triangle_order() const { return order_; }
  [[nodiscard]] bool empty() const { return nodes_.empty(); }
  /// Longest root-to-leaf path in edges (0 for a single leaf).
  [[nodiscard]] int depth() const { return depth_; }
  [[nodiscard]] int leaf_size() const { return leaf_size_; }

 private:
  void build(const skinning::Triangles& triangles, const skinning::Positions& positions);
  std::int32_t build_range(std::int32_t begin, std::int32_t end, int depth);

  std::vector<BvhNode> nodes_;
  std::vector<Volume> node_bounds_;
  std::vector<std::int32_t> order_;
  struct Item {
    Eigen::Vector3d centroid;
    std::int32_t id;
  };
  std::vector<Item> items_;  // build-time only, by slot; freed after the build
  int depth_ = 0;
  int leaf_size_ = 1;
};

using AabbBvh = Bvh<3>;
using KdopBvh = Bvh<8>;

}  // namespace skelcd::culling
