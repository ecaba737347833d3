#pragma once
// A small static AABB tree over triangles that answers one question: does an open segment cross
// any triangle other than those around a given vertex? (Visibility for the bone heat weights.)
// Kept here rather than in culling/, whose BVH serves swept primitives and pair traversal.

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "skinning/mesh.hpp"

namespace skelcd::segmentation::detail {

class TriangleBvh {
 public:
  /// Builds the tree (median split on the longest axis of the centroids' box).
  /// @param V #W × 3 positions; @param F #F × 3 indices into V. Both must outlive the tree.
  TriangleBvh(const skinning::Positions& V, const skinning::Triangles& F);

  /// True when the segment from `p0` (parameter 0) to `p1` (parameter 1) meets a triangle at a
  /// parameter in (0, 1), ignoring the triangles that have vertex `skip_vertex` as a corner
  /// (pass −1 to ignore none). Plain floating point (Möller–Trumbore): a graze within rounding
  /// may go either way, which is harmless for visibility.
  [[nodiscard]] bool segment_hits(
      const Eigen::Vector3d& p0,
      const Eigen::Vector3d& p1,
      std::int32_t skip_vertex) const;

  /// Calls `hit(t)` for every crossing of the line p0 + t (p1 − p0), t in (0, 1), with any
  /// triangle (used for inside/outside parity along grid rows).
  template <class Fn>
  void for_each_crossing(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, Fn&& hit) const;

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    std::int32_t first = 0;  ///< leaf: first index into order_; inner: left child (right = +1)
    std::int32_t count = 0;  ///< leaf: number of triangles; inner: 0
  };
  void build(std::int32_t node, std::int32_t begin, std::int32_t end,
             const std::vector<Eigen::Vector3d>& centroids);
  /// Ray-triangle parameter in (0,1) or a negative value when they miss.
  [[nodiscard]] double crossing(std::int32_t f, const Eigen::Vector3d& o,
                                const Eigen::Vector3d& dir) const;
  [[nodiscard]] static bool slab_overlap(const Node& n, const Eigen::Vector3d& o,
                                         const Eigen::Vector3d& inv_dir);

  const skinning::Positions& V_;
  const skinning::Triangles& F_;
  std::vector<Node> nodes_;
  std::vector<std::int32_t> order_;
};

template <class Fn>
void TriangleBvh::for_each_crossing(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                    Fn&& hit) const {
  if (nodes_.empty()) return;
  const Eigen::Vector3d dir = p1 - p0;
  const Eigen::Vector3d inv_dir = dir.cwiseInverse();
  std::int32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--top])];
    if (!slab_overlap(n, p0, inv_dir)) continue;
    if (n.count > 0) {
      for (std::int32_t k = n.first; k < n.first + n.count; ++k) {
        const double t = crossing(order_[static_cast<std::size_t>(k)], p0, dir);
        if (t > 0.0) hit(t);
      }
    } else {
      stack[top++] = n.first;
      stack[top++] = n.first + 1;
    }
  }
}

}  // namespace skelcd::segmentation::detail
