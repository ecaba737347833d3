#include "culling/cluster_checks.hpp"

#include <cassert>
#include <limits>
#include <utility>

namespace skelcd::culling {
namespace {

using Entry = TraversalScratch::Entry;

inline std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

inline void push(std::vector<Entry>& stack, std::int32_t a, std::int32_t b) {
  assert(stack.size() < stack.capacity());  // the reserve_* bounds hold for masked traversals too
  stack.push_back({a, b});
}

constexpr std::uint8_t kSigns = kMaskPositive | kMaskNegative;

/// Can a node pair with masks ma, mb hold a pair that `which` selects?
inline bool node_pair_wanted(std::uint8_t ma, std::uint8_t mb, MaskedPairs which) {
  if (which == MaskedPairs::tested) return !mask_pair_skipped(ma, mb);
  return (ma & mb & kSigns) != 0;  // a skipped pair needs the same sign on both sides
}

inline bool pair_wanted(std::uint8_t a, std::uint8_t b, MaskedPairs which) {
  return mask_pair_skipped(a, b) == (which == MaskedPairs::skipped);
}

inline void emit(std::vector<TrianglePair>& out, std::int32_t a, std::int32_t b) {
  if (b < a) std::swap(a, b);
  out.push_back({a, b});
}

/// Leaf pairs: the triangles of two leaves (or of one leaf with itself when `same`).
template <int N>
void leaf_pairs(
    const BvhNode& la,
    std::span<const std::int32_t> order_a,
    const BvhNode& lb,
    std::span<const std::int32_t> order_b,
    bool same,
    std::span<const Dop<N>> bounds,
    std::span<const std::uint8_t> mask,
    MaskedPairs which,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  for (std::int32_t i = la.begin; i < la.end; ++i) {
    const std::int32_t ti = order_a[at(i)];
    for (std::int32_t j = same ? i + 1 : lb.begin; j < lb.end; ++j) {
      const std::int32_t tj = order_b[at(j)];
      if (!pair_wanted(mask[at(ti)], mask[at(tj)], which)) continue;
      ++bv_tests;
      if (bounds[at(ti)].overlaps(bounds[at(tj)])) emit(out, ti, tj);
    }
  }
}

/// Splits the node with more triangles (a leaf is never split).
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
void node_class_masks(
    const Bvh<N>& bvh,
    std::span<const std::uint8_t> triangle_mask,
    std::vector<std::uint8_t>& out) {
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  out.resize(nodes.size());
  // Children follow their parent in depth-first order: one backward sweep is bottom-up.
  for (std::size_t n = nodes.size(); n-- > 0;) {
    const BvhNode& node = nodes[n];
    std::uint8_t m = 0;
    if (node.is_leaf()) {
      for (std::int32_t s = node.begin; s < node.end; ++s) m |= triangle_mask[at(order[at(s)])];
    } else {
      m = out[n + 1] | out[at(node.right)];
    }
    out[n] = m;
  }
}

template <int N>
void start_masked_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch) {
  scratch.reserve_self(bvh);
  scratch.stack.clear();
  if (!bvh.empty()) push(scratch.stack, 0, 0);
}

template <int N>
bool masked_self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    std::span<const std::uint8_t> node_mask,
    std::span<const std::uint8_t> triangle_mask,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs) {
  if (bvh.empty()) return true;
  const auto nodes = bvh.nodes();
  const auto bounds = bvh.node_bounds();
  const auto order = bvh.triangle_order();
  // With end boxes for this interval, node pairs are also tested in the relative motion
  // (node_end_boxes_meet; docs/culling.md "Relative boxes at the nodes").
  const auto ends = bvh.node_end_boxes();
  auto& stack = scratch.stack;
  while (!stack.empty()) {
    if (out.size() >= max_pairs) return false;
    const Entry e = stack.back();
    stack.pop_back();
    const std::uint8_t ma = node_mask[at(e.a)];
    const std::uint8_t mb = node_mask[at(e.b)];
    // A node whose triangles are all one sign holds no pair to test (and, for `skipped`, a node
    // pair without a common sign holds none to re-check): no volume test needed either.
    if (!node_pair_wanted(ma, mb, which)) continue;
    const BvhNode& na = nodes[at(e.a)];
    if (e.a == e.b) {
      if (na.is_leaf()) {
        leaf_pairs<N>(na, order, na, order, true, triangle_bounds, triangle_mask, which, out,
                      bv_tests);
      } else {
        push(stack, e.a + 1, na.right);
        push(stack, na.right, na.right);
        push(stack, e.a + 1, e.a + 1);
      }
      continue;
    }
    ++bv_tests;
    if (!bounds[at(e.a)].overlaps(bounds[at(e.b)])) continue;
    if (!ends.empty() && !node_end_boxes_meet(ends[at(e.a)], ends[at(e.b)])) continue;
    const BvhNode& nb = nodes[at(e.b)];
    if (na.is_leaf() && nb.is_leaf()) {
      leaf_pairs<N>(na, order, nb, order, false, triangle_bounds, triangle_mask, which, out,
                    bv_tests);
    } else {
      split_pair(stack, e.a, na, e.b, nb);
    }
  }
  return true;
}

template <int N>
void masked_self_traverse(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    std::span<const std::uint8_t> node_mask,
    std::span<const std::uint8_t> triangle_mask,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_masked_self_traversal(bvh, scratch);
  masked_self_traverse_some(
      bvh,
      triangle_bounds,
      node_mask,
      triangle_mask,
      which,
      scratch,
      out,
      bv_tests,
      std::numeric_limits<std::size_t>::max());
}

template <int N>
void start_masked_pair_traversal(const Bvh<N>& a, const Bvh<N>& b, TraversalScratch& scratch) {
  scratch.reserve_pair(a, b);
  scratch.stack.clear();
  if (!a.empty() && !b.empty()) push(scratch.stack, 0, 0);
}

template <int N>
bool masked_pair_traverse_some(
    const Bvh<N>& a,
    std::span<const std::uint8_t> node_mask_a,
    const Bvh<N>& b,
    std::span<const std::uint8_t> node_mask_b,
    std::span<const Dop<N>> triangle_bounds,
    std::span<const std::uint8_t> triangle_mask,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs) {
  if (a.empty() || b.empty()) return true;
  const auto nodes_a = a.nodes();
  const auto nodes_b = b.nodes();
  const auto ends_a = a.node_end_boxes();
  const auto ends_b = b.node_end_boxes();
  const bool relative = !ends_a.empty() && !ends_b.empty();
  auto& stack = scratch.stack;
  while (!stack.empty()) {
    if (out.size() >= max_pairs) return false;
    const Entry e = stack.back();
    stack.pop_back();
    if (!node_pair_wanted(node_mask_a[at(e.a)], node_mask_b[at(e.b)], which)) continue;
    ++bv_tests;
    if (!a.node_bounds()[at(e.a)].overlaps(b.node_bounds()[at(e.b)])) continue;
    if (relative && !node_end_boxes_meet(ends_a[at(e.a)], ends_b[at(e.b)])) continue;
    const BvhNode& na = nodes_a[at(e.a)];
    const BvhNode& nb = nodes_b[at(e.b)];
    if (na.is_leaf() && nb.is_leaf()) {
      leaf_pairs<N>(na, a.triangle_order(), nb, b.triangle_order(), false, triangle_bounds,
                    triangle_mask, which, out, bv_tests);
      continue;
    }
    split_pair(stack, e.a, na, e.b, nb);
  }
  return true;
}

template <int N>
void masked_pair_traverse(
    const Bvh<N>& a,
    std::span<const std::uint8_t> node_mask_a,
    const Bvh<N>& b,
    std::span<const std::uint8_t> node_mask_b,
    std::span<const Dop<N>> triangle_bounds,
    std::span<const std::uint8_t> triangle_mask,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_masked_pair_traversal(a, b, scratch);
  masked_pair_traverse_some(
      a,
      node_mask_a,
      b,
      node_mask_b,
      triangle_bounds,
      triangle_mask,
      which,
      scratch,
      out,
      bv_tests,
      std::numeric_limits<std::size_t>::max());
}

template void node_class_masks<3>(
    const Bvh<3>&, std::span<const std::uint8_t>, std::vector<std::uint8_t>&);
template void node_class_masks<8>(
    const Bvh<8>&, std::span<const std::uint8_t>, std::vector<std::uint8_t>&);
template void masked_self_traverse<3>(
    const Bvh<3>&, std::span<const Dop<3>>, std::span<const std::uint8_t>,
    std::span<const std::uint8_t>, MaskedPairs, TraversalScratch&, std::vector<TrianglePair>&,
    std::int64_t&);
template void masked_self_traverse<8>(
    const Bvh<8>&, std::span<const Dop<8>>, std::span<const std::uint8_t>,
    std::span<const std::uint8_t>, MaskedPairs, TraversalScratch&, std::vector<TrianglePair>&,
    std::int64_t&);
template void masked_pair_traverse<3>(
    const Bvh<3>&, std::span<const std::uint8_t>, const Bvh<3>&, std::span<const std::uint8_t>,
    std::span<const Dop<3>>, std::span<const std::uint8_t>, MaskedPairs, TraversalScratch&,
    std::vector<TrianglePair>&, std::int64_t&);
template void masked_pair_traverse<8>(
    const Bvh<8>&, std::span<const std::uint8_t>, const Bvh<8>&, std::span<const std::uint8_t>,
    std::span<const Dop<8>>, std::span<const std::uint8_t>, MaskedPairs, TraversalScratch&,
    std::vector<TrianglePair>&, std::int64_t&);

template void start_masked_self_traversal<3>(const Bvh<3>&, TraversalScratch&);
template void start_masked_self_traversal<8>(const Bvh<8>&, TraversalScratch&);
template bool masked_self_traverse_some<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    std::span<const std::uint8_t>,
    std::span<const std::uint8_t>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool masked_self_traverse_some<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    std::span<const std::uint8_t>,
    std::span<const std::uint8_t>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template void start_masked_pair_traversal<3>(const Bvh<3>&, const Bvh<3>&, TraversalScratch&);
template void start_masked_pair_traversal<8>(const Bvh<8>&, const Bvh<8>&, TraversalScratch&);
template bool masked_pair_traverse_some<3>(
    const Bvh<3>&,
    std::span<const std::uint8_t>,
    const Bvh<3>&,
    std::span<const std::uint8_t>,
    std::span<const Dop<3>>,
    std::span<const std::uint8_t>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool masked_pair_traverse_some<8>(
    const Bvh<8>&,
    std::span<const std::uint8_t>,
    const Bvh<8>&,
    std::span<const std::uint8_t>,
    std::span<const Dop<8>>,
    std::span<const std::uint8_t>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);

}  // namespace skelcd::culling
