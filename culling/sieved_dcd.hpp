#pragma once
// The DCD self traversal of one hierarchy shared by `bvh`, `kdop`, `auto` and `dynamic`'s
// detect_dcd: the tree against itself in installments into a DCD query's blocks, the pairs that
// share a vertex whose fan is certified at the instant settled where the traversal meets them
// (FanSieve, culling/traversal.hpp; docs/culling.md "DCD").

#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "culling/pair_blocks.hpp"
#include "culling/traversal.hpp"

namespace skelcd::culling {

/// The pairs of `bvh` (refit to the instant's static volumes `triangle_bounds`) into `blocks`,
/// which start_dcd has started at that instant (its certified fans drive the sieve; none: no
/// sieve). `slots` is SlotAdjacency(topology, bvh.triangle_order()); `full_slots` a buffer
/// (resized to #slots). Settled pairs are counted as candidates in out.counters, as the DCD filter
/// counts the pairs it keeps.
template <int N>
void sieved_self_dcd(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    const FeatureTopology& topology,
    const SlotAdjacency& slots,
    std::vector<std::uint8_t>& full_slots,
    TraversalScratch& scratch,
    PairBlocks<N>& blocks,
    FrameResult& out) {
  start_self_traversal<N>(bvh, scratch);
  FanSieve sieve = fan_sieve(slots, blocks.fans(), full_slots, topology);
  // The tests of a block beside the next installment when they have threads to spare: the
  // traversal writes bv_tests and its own sieve only.
  blocks.drain_overlapped([&](std::vector<TrianglePair>& pairs, std::size_t max_pairs) {
    return self_traverse_some<N>(
        bvh, triangle_bounds, scratch, pairs, out.counters.bv_tests, max_pairs, &sieve);
  });
  out.counters.candidate_pairs += sieve.settled;
}

}  // namespace skelcd::culling
