#include "culling/traversal.hpp"

#include <algorithm>
#include <cassert>
#include <cstdint>
#include <limits>
#include <utility>

namespace skelcd::culling {
namespace {

using Entry = TraversalScratch::Entry;

inline void push(std::vector<Entry>& stack, std::int32_t a, std::int32_t b) {
  // The reserve_* bounds are proven; growing here would mean the proof is wrong.
  assert(stack.size() < stack.capacity());
  stack.push_back({a, b});
}

inline std::size_t to_size(std::int32_t i) { return static_cast<std::size_t>(i); }

/// Appends a pair: ordered a < b within one tree (`self_tree`), as given across two trees.
inline void emit(std::vector<TrianglePair>& out, std::int32_t ta, std::int32_t tb, bool self_tree) {
  if (self_tree && tb < ta) std::swap(ta, tb);
  out.push_back({ta, tb});
}

/// The triangle pairs of two leaves (or of one leaf with itself when `same`), of one tree when
/// `self_tree`.
template <int N>
void leaf_pairs(
    const BvhNode& la,
    std::span<const std::int32_t> order_a,
    std::span<const Dop<N>> bounds_a,
    const BvhNode& lb,
    std::span<const std::int32_t> order_b,
    std::span<const Dop<N>> bounds_b,
    bool same,
    bool self_tree,
    bool single_triangle_leaves,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  if (same) {
    for (std::int32_t i = la.begin; i < la.end; ++i) {
      const std::int32_t ti = order_a[to_size(i)];
      for (std::int32_t j = i + 1; j < la.end; ++j) {
        const std::int32_t tj = order_a[to_size(j)];
        ++bv_tests;
        if (bounds_a[to_size(ti)].overlaps(bounds_a[to_size(tj)])) emit(out, ti, tj, true);
      }
    }
    return;
  }
  if (single_triangle_leaves) {
    // A one-triangle leaf's volume is its triangle's: the node test just made was this test.
    emit(out, order_a[to_size(la.begin)], order_b[to_size(lb.begin)], self_tree);
    return;
  }
  for (std::int32_t i = la.begin; i < la.end; ++i) {
    const std::int32_t ti = order_a[to_size(i)];
    for (std::int32_t j = lb.begin; j < lb.end; ++j) {
      const std::int32_t tj = order_b[to_size(j)];
      ++bv_tests;
      if (bounds_a[to_size(ti)].overlaps(bounds_b[to_size(tj)])) emit(out, ti, tj, self_tree);
    }
  }
}

/// Descends a node pair whose volumes overlap and are not both leaves: splits the node with
/// more triangles (a leaf is never split). Node ids a and b may belong to different trees.
inline void split_pair(
    std::vector<Entry>& stack,
    std::int32_t a,
    const BvhNode& na,
    std::int32_t b,
    const BvhNode& nb) {
  if (nb.is_leaf() || (!na.is_leaf() && na.size() >= nb.size())) {
    push(stack, na.right, b);
    push(stack, a + 1, b);
  } else {
    push(stack, a, nb.right);
    push(stack, a, b + 1);
  }
}

}  // namespace

template <int N>
void start_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch) {
  scratch.reserve_self(bvh);
  scratch.stack.clear();
  if (!bvh.empty()) push(scratch.stack, 0, 0);
}

template <int N>
bool self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs) {
  if (bvh.empty()) return true;
  const auto nodes = bvh.nodes();
  const auto bounds = bvh.node_bounds();
  const auto order = bvh.triangle_order();
  const bool single = bvh.leaf_size() == 1;
  auto& stack = scratch.stack;
  while (!stack.empty()) {
    if (out.size() >= max_pairs) return false;
    const Entry e = stack.back();
    stack.pop_back();
    const BvhNode& na = nodes[to_size(e.a)];
    if (e.a == e.b) {
      // A node against itself: pairs inside each child, then pairs across the two children.
      if (na.is_leaf()) {
        leaf_pairs<N>(
            na,
            order,
            triangle_bounds,
            na,
            order,
            triangle_bounds,
            true,
            true,
            single,
            out,
            bv_tests);
      } else {
        push(stack, e.a + 1, na.right);
        push(stack, na.right, na.right);
        push(stack, e.a + 1, e.a + 1);
      }
      continue;
    }
    ++bv_tests;
    if (!bounds[to_size(e.a)].overlaps(bounds[to_size(e.b)])) continue;
    const BvhNode& nb = nodes[to_size(e.b)];
    if (na.is_leaf() && nb.is_leaf()) {
      leaf_pairs<N>(
          na,
          order,
          triangle_bounds,
          nb,
          order,
          triangle_bounds,
          false,
          true,
          single,
          out,
          bv_tests);
    } else {
      split_pair(stack, e.a, na, e.b, nb);
    }
  }
  return true;
}

template <int N>
void self_traverse(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_self_traversal(bvh, scratch);
  self_traverse_some(
      bvh, triangle_bounds, scratch, out, bv_tests, std::numeric_limits<std::size_t>::max());
}

template <int N>
void start_pair_traversal(const Bvh<N>& a, const Bvh<N>& b, TraversalScratch& scratch) {
  scratch.reserve_pair(a, b);
  scratch.stack.clear();
  if (!a.empty() && !b.empty()) push(scratch.stack, 0, 0);
}

template <int N>
bool pair_traverse_some(
    const Bvh<N>& a,
    std::span<const Dop<N>> triangle_bounds_a,
    const Bvh<N>& b,
    std::span<const Dop<N>> triangle_bounds_b,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs) {
  if (a.empty() || b.empty()) return true;
  const auto nodes_a = a.nodes();
  const auto nodes_b = b.nodes();
  const bool single = a.leaf_size() == 1 && b.leaf_size() == 1;
  auto& stack = scratch.stack;
  while (!stack.empty()) {
    if (out.size() >= max_pairs) return false;
    const Entry e = stack.back();
    stack.pop_back();
    ++bv_tests;
    if (!a.node_bounds()[to_size(e.a)].overlaps(b.node_bounds()[to_size(e.b)])) continue;
    const BvhNode& na = nodes_a[to_size(e.a)];
    const BvhNode& nb = nodes_b[to_size(e.b)];
    if (na.is_leaf() && nb.is_leaf()) {
      leaf_pairs<N>(
          na,
          a.triangle_order(),
          triangle_bounds_a,
          nb,
          b.triangle_order(),
          triangle_bounds_b,
          false,
          false,
          single,
          out,
          bv_tests);
      continue;
    }
    split_pair(stack, e.a, na, e.b, nb);
  }
  return true;
}

template <int N>
void pair_traverse(
    const Bvh<N>& a,
    std::span<const Dop<N>> triangle_bounds_a,
    const Bvh<N>& b,
    std::span<const Dop<N>> triangle_bounds_b,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_pair_traversal(a, b, scratch);
  pair_traverse_some(
      a,
      triangle_bounds_a,
      b,
      triangle_bounds_b,
      scratch,
      out,
      bv_tests,
      std::numeric_limits<std::size_t>::max());
}

template void start_self_traversal<3>(const Bvh<3>&, TraversalScratch&);
template void start_self_traversal<8>(const Bvh<8>&, TraversalScratch&);
template bool self_traverse_some<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool self_traverse_some<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template void self_traverse<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void self_traverse<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void start_pair_traversal<3>(const Bvh<3>&, const Bvh<3>&, TraversalScratch&);
template void start_pair_traversal<8>(const Bvh<8>&, const Bvh<8>&, TraversalScratch&);
template bool pair_traverse_some<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    const Bvh<3>&,
    std::span<const Dop<3>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool pair_traverse_some<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    const Bvh<8>&,
    std::span<const Dop<8>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template void pair_traverse<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    const Bvh<3>&,
    std::span<const Dop<3>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void pair_traverse<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    const Bvh<8>&,
    std::span<const Dop<8>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);

}  // namespace skelcd::culling
