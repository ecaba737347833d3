#pragma once
// Bounding volume test tree (BVTT) traversals: one hierarchy against itself (self-collision) and
// two hierarchies against each other (inter-object). They report triangle pairs whose volumes
// overlap; what to test inside a pair is the caller's business (culling/candidates.hpp).

#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/frame_result.hpp"

namespace skelcd::culling {

/// Caller-owned scratch of a traversal: the stack of pending node pairs. Reserve it once for the
/// hierarchies it will traverse; a traversal then allocates nothing. One per thread when
/// traversals run in parallel (a stack seeded with a frontier of node pairs is the unit to split).
struct TraversalScratch {
  struct Entry {
    std::int32_t a;
    std::int32_t b;
  };
  std::vector<Entry> stack;

  /// Reserves the proven maximum stack size of self_traverse(bvh): 4·depth + 1 entries (the
  /// self part of a path descends at most depth levels leaving two siblings pending each, the
  /// pair part at most 2·depth levels leaving one).
  template <int N>
  void reserve_self(const Bvh<N>& bvh) {
    reserve(4 * static_cast<std::size_t>(bvh.depth()) + 4);
  }
  /// Reserves the maximum stack size of pair_traverse(a, b): depth(a) + depth(b) + 1.
  template <int N>
  void reserve_pair(const Bvh<N>& a, const Bvh<N>& b) {
    reserve(static_cast<std::size_t>(a.depth() + b.depth()) + 4);
  }
  void reserve(std::size_t n) {
    if (stack.capacity() < n) stack.reserve(n);
  }
};

/// Self traversal: appends to `out` every pair of distinct triangles (a < b) of `bvh` whose
/// volumes in `triangle_bounds` overlap — exactly those, each once (tests/culling prove it against
/// all pairs). Node vs itself → both children vs themselves and the children against each other;
/// two nodes → their volumes are tested and the one with more triangles is split.
/// @param triangle_bounds indexed by triangle id; the volumes `bvh` was refit from.
/// @param bv_tests incremented once per node-pair and triangle-pair volume test.
/// @note Allocation-free once `scratch` is reserved and `out` has the capacity.
template <int N>
void self_traverse(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests);

/// The self traversal in installments, so that its pairs can be tested in bounded blocks
/// (bounded memory on any motion): start_self_traversal seeds `scratch`; each self_traverse_some
/// appends pairs until `out` holds at least `max_pairs` (it may pass that by one leaf pair's
/// pairs, at most leaf_size² − 1) and returns true once the traversal is finished. Over all
/// installments the pairs are exactly self_traverse's, each once; `scratch` must not be used for
/// anything else in between.
template <int N>
void start_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch);
template <int N>
bool self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs);

/// Pair traversal: appends to `out` every (triangle of a, triangle of b) whose volumes overlap,
/// each once; `TrianglePair::a` is a triangle id of `a`'s triangles, `TrianglePair::b` of `b`'s.
template <int N>
void pair_traverse(
    const Bvh<N>& a,
    std::span<const Dop<N>> triangle_bounds_a,
    const Bvh<N>& b,
    std::span<const Dop<N>> triangle_bounds_b,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests);

/// The pair traversal in installments, as start_self_traversal / self_traverse_some: over all
/// installments the pairs are exactly pair_traverse's, each once, in the same order.
template <int N>
void start_pair_traversal(const Bvh<N>& a, const Bvh<N>& b, TraversalScratch& scratch);
template <int N>
bool pair_traverse_some(
    const Bvh<N>& a,
    std::span<const Dop<N>> triangle_bounds_a,
    const Bvh<N>& b,
    std::span<const Dop<N>> triangle_bounds_b,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs);

}  // namespace skelcd::culling
