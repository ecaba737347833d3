#include "culling/bvh.hpp"

#include <algorithm>
#include <numeric>
#include <string>

#include "skinning/errors.hpp"

namespace skelcd::culling {

template <int N>
Bvh<N>::Bvh(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    const BvhOptions& options)
    : leaf_size_(options.leaf_size) {
  order_.resize(static_cast<std::size_t>(triangles.rows()));
  std::iota(order_.begin(), order_.end(), 0);
  build(triangles, positions);
}

template <int N>
Bvh<N>::Bvh(
    const skinning::Triangles& triangles,
    const skinning::Positions& positions,
    std::span<const std::int32_t> subset,
    const BvhOptions& options)
    : order_(subset.begin(), subset.end()), leaf_size_(options.leaf_size) {
  for (std::size_t i = 0; i < order_.size(); ++i) {
    if (order_[i] < 0 || order_[i] >= triangles.rows()) {
      throw InvalidInput(
          "culling::Bvh: subset entry " + std::to_string(i) + " is triangle " +
          std::to_string(order_[i]) + ", outside [0, " + std::to_string(triangles.rows()) + ")");
    }
  }
  build(triangles, positions);
}

template <int N>
void Bvh<N>::build(const skinning::Triangles& triangles, const skinning::Positions& positions) {
  if (leaf_size_ < 1) {
    throw InvalidInput(
        "culling::Bvh: leaf_size must be at least 1, got " + std::to_string(leaf_size_));
  }
  // Centroids (times 3: the split only compares them) of the triangles, by slot.
  items_.resize(order_.size());
  for (std::size_t i = 0; i < order_.size(); ++i) {
    const auto f = static_cast<Eigen::Index>(order_[i]);
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (Eigen::Index k = 0; k < 3; ++k) {
      const std::int32_t v = triangles(f, k);
      if (v < 0 || v >= positions.rows()) {
        throw InvalidInput(
            "culling::Bvh: triangle " + std::to_string(f) + " corner " + std::to_string(k) +
            " is vertex " + std::to_string(v) + ", outside [0, " +
            std::to_string(positions.rows()) + ")");
      }
      c += positions.row(v).transpose();
    }
    items_[i] = {c, order_[i]};
  }
  nodes_.clear();
  depth_ = 0;
  if (!order_.empty()) {
    // A binary tree with #F leaves at most has 2·#F − 1 nodes.
    nodes_.reserve(2 * order_.size() - 1);
    build_range(0, static_cast<std::int32_t>(order_.size()), 0);
  }
  for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = items_[i].id;
  node_bounds_.assign(nodes_.size(), Volume::empty());
  items_ = {};
}

template <int N>
std::int32_t Bvh<N>::build_range(std::int32_t begin, std::int32_t end, int depth) {
  const auto index = static_cast<std::int32_t>(nodes_.size());
  nodes_.push_back({begin, end, 0});
  depth_ = std::max(depth_, depth);
  if (end - begin <= leaf_size_) return index;

  // Longest axis of the centroids' bounding box.
  Eigen::Vector3d lo = items_[static_cast<std::size_t>(begin)].centroid;
  Eigen::Vector3d hi = lo;
  for (std::int32_t i = begin + 1; i < end; ++i) {
    lo = lo.cwiseMin(items_[static_cast<std::size_t>(i)].centroid);
    hi = hi.cwiseMax(items_[static_cast<std::size_t>(i)].centroid);
  }
  Eigen::Index axis = 0;
  (hi - lo).maxCoeff(&axis);

  // Median split by count: the lower half of centroids along the axis goes left. Ties are broken
  // by triangle id so the tree depends only on the input, not on the library's nth_element.
  const std::int32_t mid = begin + (end - begin) / 2;
  const auto before = [axis](const Item& s, const Item& t) {
    const double cs = s.centroid[axis];
    const double ct = t.centroid[axis];
    if (cs != ct) return cs < ct;
    return s.id < t.id;
  };
  std::nth_element(items_.begin() + begin, items_.begin() + mid, items_.begin() + end, before);

  build_range(begin, mid, depth + 1);
  const std::int32_t right = build_range(mid, end, depth + 1);
  nodes_[static_cast<std::size_t>(index)].right = right;
  return index;
}

template <int N>
void Bvh<N>::refit(std::span<const Volume> triangle_bounds) {
  // Depth-first order puts every child after its parent, so one backward sweep is bottom-up.
  for (std::size_t n = nodes_.size(); n-- > 0;) {
    const BvhNode& node = nodes_[n];
    Volume v;
    if (node.is_leaf()) {
      v = triangle_bounds[static_cast<std::size_t>(order_[static_cast<std::size_t>(node.begin)])];
      for (std::int32_t s = node.begin + 1; s < node.end; ++s) {
        v.merge(triangle_bounds[static_cast<std::size_t>(order_[static_cast<std::size_t>(s)])]);
      }
    } else {
      v = node_bounds_[n + 1];
      v.merge(node_bounds_[static_cast<std::size_t>(node.right)]);
    }
    node_bounds_[n] = v;
  }
}

template class Bvh<3>;
template class Bvh<8>;

}  // namespace skelcd::culling
