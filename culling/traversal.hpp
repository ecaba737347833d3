#pragma once
// Bounding volume test tree (BVTT) traversals: one hierarchy against itself (self-collision) and
// two hierarchies against each other (inter-object). They report triangle pairs whose volumes
// overlap; what to test inside a pair is the caller's business (culling/candidates.hpp).

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/frame_result.hpp"

namespace skelcd::culling {

class FeatureTopology;

/// The static half of a FanSieve, for one hierarchy: its triangles' corners by slot of
/// Bvh::triangle_order, and which slots near each other share a vertex.
struct SlotAdjacency {
  /// Half the window: window[s] covers the slots s − kReach .. s + kReach − 1.
  static constexpr std::int32_t kReach = 32;

  SlotAdjacency() = default;
  SlotAdjacency(const FeatureTopology& topology, std::span<const std::int32_t> order);

  /// corners[s]: the vertex ids of triangle order[s], then −1; all four −1 for a triangle that
  /// repeats a vertex (never settled).
  std::vector<std::array<std::int32_t, 4>> corners;
  /// Bit d of window[s] (d ≠ kReach) is set when the triangles in slots s and s + d − kReach
  /// share one or two vertices and their parts are not excluded — the pairs a certified vertex
  /// settles when every corner of slot s is certified, as a mask to take four at a time.
  std::vector<std::uint64_t> window;
};

/// What a DCD self traversal settles instead of emitting (docs/culling.md "DCD"): two triangles
/// that share a vertex whose fan is certified at the instant (culling/vertex_fans.hpp) have no
/// common point beyond what they share, so the pair needs no test. `bvh`'s and `kdop`'s CCD
/// traversals use it too, with the fans certified over the interval (docs/culling.md "Vertex fans
/// over an interval"): such a pair has no feature pair to test. Those pairs are 80–95 % of a
/// DCD's candidates on real meshes; dropping them where the traversal finds them saves their
/// emission, their block and their filter. The pairs the sieve lets through are exactly the
/// others: a pair sharing no certified vertex, one sharing three vertices (a duplicate face, which
/// the DCD filter drops) and any pair with a degenerate triangle.
struct FanSieve {
  const SlotAdjacency* slots = nullptr;
  /// Per vertex: its fan is certified at the instant (VertexFans::certify).
  std::span<const std::uint8_t> certified;
  /// Per slot: all three corners are certified (certified_slots); filled by the caller.
  std::span<const std::uint8_t> full;
  /// For its part-pair exclusions: a settled pair of excluded parts is no candidate.
  const FeatureTopology* topology = nullptr;
  /// Settled pairs that are candidates (not excluded), as the DCD filter would count them.
  std::int64_t settled = 0;
};

/// FanSieve::full of `slots` for the instant's `certified` vertices, into `full` (resized).
void certified_slots(
    const SlotAdjacency& slots,
    std::span<const std::uint8_t> certified,
    std::vector<std::uint8_t>& full);

/// A FanSieve over `slots` for the `certified` vertices, its FanSieve::full computed into `full`
/// (left empty, as the sieve, when no vertex list is given: it then settles nothing).
FanSieve fan_sieve(
    const SlotAdjacency& slots,
    std::span<const std::uint8_t> certified,
    std::vector<std::uint8_t>& full,
    const FeatureTopology& topology);

/// Bit i set when child i of wide node `w` (its lane i) and lane `lane` of wide node `q` may come
/// within reach of each other over the interval, judged by their end boxes (Bvh::end_boxes;
/// docs/culling.md "Relative boxes at the nodes"): they are apart when, on some axis, one lane's
/// box lies strictly below the other's both at t = 0 and at t = 1. For points x(t) and y(t) of
/// the two lanes' triangles, moving linearly, y_k(t) − x_k(t) is linear in t, so positive at both
/// ends it is positive in between: no point of one lane reaches a point of the other over [0, 1]
/// (nor within 2·half_width, the boxes being grown by it). The boxes are floats rounded outwards,
/// so strict gaps between them are gaps between the exact ends. This is a test in the motion
/// relative to any common velocity at once — stronger than the hull of the box at t = 0 and the
/// box at t = 1 shifted by one chosen u, which it replaced — and it needs no arithmetic. Bits of
/// unused lanes are 0. The self and pair traversals apply it to every node pair when both trees
/// have end boxes. Only the lanes in `wanted` are looked at (the others' bits are 0).
[[nodiscard]] unsigned end_boxes_meet(
    const WideEndBoxes& w, const WideEndBoxes& q, int lane, unsigned wanted = 0xfu);

/// Caller-owned scratch of a traversal: the stack of pending node pairs. Reserve it once for the
/// hierarchies it will traverse; a traversal then allocates nothing. One per thread when
/// traversals run in parallel (a stack seeded with a frontier of node pairs is the unit to split).
struct TraversalScratch {
  struct Entry {
    std::int32_t a;
    std::int32_t b;
  };
  std::vector<Entry> stack;
  /// Triangle pairs self_traverse_some dropped in the leaves as apart at both ends (when the tree
  /// has its slot end boxes, Bvh::refit_slot_ends), added up until the caller resets it.
  std::int64_t apart_at_both_ends = 0;

  /// Reserves the proven maximum stack size of a self traversal of `bvh` over its wide nodes
  /// (self_traverse, and the masked one of culling/cluster_checks.hpp, which pushes a subset):
  /// 9·(wide_depth − 1) + 1 entries — an entry's processing pushes at most one entry per child or
  /// per two children (a node against itself: 4 + 6, so 9 left pending besides the one processed
  /// next; two nodes: 4, so 3), and a path descends at most wide_depth − 1 self levels from the
  /// root, then at most 2·(wide_depth − L) pair levels below self level L.
  template <int N>
  void reserve_self(const Bvh<N>& bvh) {
    reserve(9 * static_cast<std::size_t>(bvh.wide_depth()) + 4);
  }
  /// Reserves the maximum stack size of a pair traversal of (a, b) (masked or not):
  /// 3·(wide_depth(a) + wide_depth(b)) + 1 (three pending per level of either tree).
  template <int N>
  void reserve_pair(const Bvh<N>& a, const Bvh<N>& b) {
    reserve(3 * static_cast<std::size_t>(a.wide_depth() + b.wide_depth()) + 4);
  }
  void reserve(std::size_t n) {
    if (stack.capacity() < n) stack.reserve(n);
  }
};

/// The rigid rows a self traversal skips this interval (culling/rigid_rows.hpp): per binary node
/// and per slot of one hierarchy, the certified row that all its triangles share, else -1. A node
/// pair or slot pair of one row ≥ 0 holds no pair to emit, and a node of a row ≥ 0 none within
/// itself.
struct RowSkip {
  std::vector<std::int32_t> nodes;  ///< #nodes (Bvh::nodes)
  std::vector<std::int32_t> slots;  ///< #slots (Bvh::triangle_order)
};

/// Fills `out` for `bvh` from each triangle's row (-1: none) and each row's certificate; returns
/// whether any node has a row (else the skip has nothing to do).
template <int N>
bool row_skip(
    const Bvh<N>& bvh,
    std::span<const std::int32_t> triangle_row,
    std::span<const std::uint8_t> certified,
    RowSkip& out);

/// Self traversal: appends to `out` every pair of distinct triangles (a < b) of `bvh` whose
/// volumes in `triangle_bounds` overlap — exactly those, each once (tests/culling prove it against
/// all pairs). Over the wide nodes (Bvh::wide_nodes): a node against itself → each child against
/// itself, and each two children whose float volumes overlap against each other; two nodes → the
/// children of the one with more triangles are tested against the other, four at once. Float
/// volumes are rounded outwards, so they let through every pair the double volumes would (and
/// a few more); a triangle pair is emitted only when its exact double volumes overlap. On a tree
/// whose slot volumes are whole (Bvh::refit_swept, both trees in a pair walk) the slots' floats on
/// every axis decide instead and `triangle_bounds` is not read (it may be empty): every pair whose
/// exact volumes overlap, and the few more whose volumes are apart by less than a float step.
/// @param triangle_bounds indexed by triangle id; the volumes `bvh` was refit from.
/// @param bv_tests incremented once per node-pair (float) and triangle-pair (double) volume test.
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
/// appends pairs until `out` holds at least `max_pairs` (it may pass that by one bucket pair's
/// pairs, at most bucket_size(leaf_size)² − 1: Bvh::wide_nodes) and returns true once the
/// traversal is finished. Over all
/// installments the pairs are exactly self_traverse's, each once; `scratch` must not be used for
/// anything else in between.
/// @param sieve (DCD) when given with certificates, the pairs it settles are counted in it instead
/// of appended: the pairs appended plus those settled or excluded are exactly self_traverse's.
/// @param rows when given, no pair of two triangles of one certified rigid row is appended, and
/// node pairs of one such row are not descended into (RowSkip).
template <int N>
void start_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch);
template <int N>
bool self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs,
    FanSieve* sieve = nullptr,
    const RowSkip* rows = nullptr);

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
