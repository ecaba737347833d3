#pragma once
// The DCD self traversal of one hierarchy shared by `bvh`, `kdop`, `auto` and `dynamic`'s
// detect_dcd: the tree against itself in installments into a DCD query's blocks, the pairs that
// share a vertex whose fan is certified at the instant settled where the traversal meets them
// (FanSieve, culling/traversal.hpp; docs/culling.md "DCD").

#include <chrono>
#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
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

/// A whole DCD query at the welded positions `x` through `bvh` (`bvh`'s and `kdop`'s, and
/// `dynamic`'s detect_dcd over its own tree): the triangles' static volumes into `bounds`, the tree
/// refit over them, `blocks` started at x with `tests`, sieved_self_dcd, the blocks finished; its
/// refit, traversal and test times added to out.times.
template <int N>
void sieved_dcd_at(
    const skinning::Positions& x,
    Bvh<N>& bvh,
    FeatureBounds<N>& bounds,
    const FeatureTopology& topology,
    const SlotAdjacency& slots,
    std::vector<std::uint8_t>& full_slots,
    TraversalScratch& scratch,
    PairBlocks<N>& blocks,
    const ElementaryTests& tests,
    FrameResult& out) {
  using Clock = std::chrono::steady_clock;
  const auto micros = [](Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double, std::micro>(to - from).count();
  };
  const auto t0 = Clock::now();
  bounds.static_triangles(topology, x);
  bvh.refit(bounds.triangles);
  const auto t1 = Clock::now();
  // Self traversal → overlapping triangle pairs → the DCD rules → tests, in blocks as the CCD
  // (bounded memory), the vertex fans certified once for the instant.
  blocks.start_dcd(topology, x, tests, out);
  sieved_self_dcd<N>(bvh, bounds.triangles, topology, slots, full_slots, scratch, blocks, out);
  blocks.finish();
  const auto t2 = Clock::now();
  out.times.refit_us += micros(t0, t1);
  out.times.traverse_us += micros(t1, t2) - blocks.test_us();
  out.times.elementary_us += blocks.test_us();
}

}  // namespace skelcd::culling
