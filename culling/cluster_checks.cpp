#include "culling/cluster_checks.hpp"

#include <algorithm>
#include <cassert>
#include <cstddef>
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

}  // namespace

template <int N>
void node_class_masks(
    const Bvh<N>& bvh, std::span<const std::uint8_t> triangle_mask, ClassMasks& out) {
  const auto nodes = bvh.nodes();
  const auto order = bvh.triangle_order();
  out.slots.resize(bvh.slot_stride());
  for (std::size_t s = 0; s < order.size(); ++s) out.slots[s] = triangle_mask[at(order[s])];
  std::fill(out.slots.begin() + static_cast<std::ptrdiff_t>(order.size()), out.slots.end(), 0);
  out.nodes.resize(nodes.size());
  // Children follow their parent in depth-first order: one backward sweep is bottom-up.
  for (std::size_t n = nodes.size(); n-- > 0;) {
    const BvhNode& node = nodes[n];
    std::uint8_t m = 0;
    if (node.is_leaf()) {
      for (std::int32_t s = node.begin; s < node.end; ++s) m |= out.slots[at(s)];
    } else {
      m = out.nodes[n + 1] | out.nodes[at(node.right)];
    }
    out.nodes[n] = m;
  }
}

template <int N>
void start_masked_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch) {
  scratch.reserve_self(bvh);
  scratch.stack.clear();
  if (!bvh.empty()) push(scratch.stack, 0, 0);
}

template <int N>
void masked_self_traverse(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    const ClassMasks& masks,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_masked_self_traversal(bvh, scratch);
  masked_self_traverse_some(
      bvh,
      triangle_bounds,
      masks,
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
void masked_pair_traverse(
    const Bvh<N>& a,
    const ClassMasks& masks_a,
    const Bvh<N>& b,
    const ClassMasks& masks_b,
    std::span<const Dop<N>> triangle_bounds,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests) {
  start_masked_pair_traversal(a, b, scratch);
  masked_pair_traverse_some(
      a,
      masks_a,
      b,
      masks_b,
      triangle_bounds,
      which,
      scratch,
      out,
      bv_tests,
      std::numeric_limits<std::size_t>::max());
}

template void node_class_masks<3>(const Bvh<3>&, std::span<const std::uint8_t>, ClassMasks&);
template void node_class_masks<8>(const Bvh<8>&, std::span<const std::uint8_t>, ClassMasks&);
template void masked_self_traverse<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    const ClassMasks&,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void masked_self_traverse<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    const ClassMasks&,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void masked_pair_traverse<3>(
    const Bvh<3>&,
    const ClassMasks&,
    const Bvh<3>&,
    const ClassMasks&,
    std::span<const Dop<3>>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);
template void masked_pair_traverse<8>(
    const Bvh<8>&,
    const ClassMasks&,
    const Bvh<8>&,
    const ClassMasks&,
    std::span<const Dop<8>>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&);

template void start_masked_self_traversal<3>(const Bvh<3>&, TraversalScratch&);
template void start_masked_self_traversal<8>(const Bvh<8>&, TraversalScratch&);
template void start_masked_pair_traversal<3>(const Bvh<3>&, const Bvh<3>&, TraversalScratch&);
template void start_masked_pair_traversal<8>(const Bvh<8>&, const Bvh<8>&, TraversalScratch&);

}  // namespace skelcd::culling
