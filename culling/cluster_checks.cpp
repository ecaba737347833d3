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
template void start_masked_pair_traversal<3>(const Bvh<3>&, const Bvh<3>&, TraversalScratch&);
template void start_masked_pair_traversal<8>(const Bvh<8>&, const Bvh<8>&, TraversalScratch&);

}  // namespace skelcd::culling
