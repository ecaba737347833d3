#pragma once
// The traversals the radial-view methods drive (paper 002, §6). Inside a mega cluster a pair of
// triangles whose features are all positively oriented to the mega cluster's observer (or all
// negatively) needs no test (docs/radial-view.md); every other pair does. Each triangle carries a
// *class mask* — one bit: positive, negative or other — and each hierarchy node the union of its
// triangles' bits, so a node pair whose two masks are the same single sign is skipped without
// descending. The masked traversals walk the wide copy of the hierarchy as the unmasked ones do
// (culling/traversal.cpp), a lane's mask being its binary node's. Pairs from different mega
// clusters are traversed without masks (traversal.hpp).

#include <cstdint>
#include <span>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/frame_result.hpp"
#include "culling/traversal.hpp"

namespace skelcd::culling {

/// Class-mask bits.
inline constexpr std::uint8_t kMaskPositive = 1;  ///< all the triangle's features H⁺
inline constexpr std::uint8_t kMaskNegative = 2;  ///< all the triangle's features H⁻
inline constexpr std::uint8_t kMaskOther = 4;     ///< anything else: tested against everything

/// True when no pair between two sets of triangles with class masks a and b needs a test: both
/// sets are of one and the same sign. (For single triangles: both positive or both negative.)
[[nodiscard]] inline bool mask_pair_skipped(std::uint8_t a, std::uint8_t b) {
  return a == b && (a == kMaskPositive || a == kMaskNegative);
}

/// Which pairs a masked traversal reports.
enum class MaskedPairs : std::uint8_t {
  tested,   ///< pairs that need a test (not mask_pair_skipped)
  skipped,  ///< exactly the pairs a `tested` traversal leaves out (for re-checking them)
};

/// Can two sets of triangles with masks a and b (two hierarchy nodes) hold a pair `which`
/// selects?
[[nodiscard]] inline bool node_pair_wanted(std::uint8_t a, std::uint8_t b, MaskedPairs which) {
  if (which == MaskedPairs::tested) return !mask_pair_skipped(a, b);
  return (a & b & (kMaskPositive | kMaskNegative)) != 0;  // a skipped pair: one sign on both sides
}

/// Does `which` select the pair of two triangles with masks a and b?
[[nodiscard]] inline bool pair_wanted(std::uint8_t a, std::uint8_t b, MaskedPairs which) {
  return mask_pair_skipped(a, b) == (which == MaskedPairs::skipped);
}

/// The class masks a masked traversal of one hierarchy reads: each binary node's (the OR over its
/// triangles, tested per wide lane through WideBvhNode::node) and each slot's (the mask of the
/// triangle at that position of triangle_order(): a bucket's four slots are tested at once).
struct ClassMasks {
  std::vector<std::uint8_t> nodes;  ///< #nodes
  std::vector<std::uint8_t> slots;  ///< Bvh::slot_stride(): four can be read from any slot
};

/// The class masks of `bvh` (ClassMasks) from the triangles' masks.
/// @param triangle_mask indexed by triangle id.  @param out resized, its memory kept.
template <int N>
void node_class_masks(
    const Bvh<N>& bvh, std::span<const std::uint8_t> triangle_mask, ClassMasks& out);

/// Self traversal of one hierarchy with masks: appends every pair a < b of its triangles whose
/// volumes overlap and that `which` selects, each once. Counts node-pair and triangle-pair
/// volume tests in bv_tests.
/// @param masks node_class_masks(bvh, triangle_mask).
/// @note Allocation-free once `scratch` is reserved (reserve_self) and `out` has the capacity.
template <int N>
void masked_self_traverse(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    const ClassMasks& masks,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests);

/// The masked self traversal in installments, so that its pairs can be tested in bounded blocks
/// (culling/pair_blocks.hpp), as start_self_traversal / self_traverse_some (traversal.hpp): each
/// masked_self_traverse_some appends pairs until `out` holds at least `max_pairs` (passing it by at
/// most one leaf pair's pairs) and returns true once finished. Over all installments the pairs are
/// exactly masked_self_traverse's, in the same order, with the same bv_tests; `scratch` must not be
/// used for anything else in between.
template <int N>
void start_masked_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch);
template <int N>
bool masked_self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    const ClassMasks& masks,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs);

/// Pair traversal of two hierarchies (two atomic clusters of one mega cluster) with masks:
/// appends every (triangle of a, triangle of b) whose volumes overlap and that `which` selects.
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
    std::int64_t& bv_tests);

/// The masked pair traversal in installments, as masked_self_traverse_some.
template <int N>
void start_masked_pair_traversal(const Bvh<N>& a, const Bvh<N>& b, TraversalScratch& scratch);
template <int N>
bool masked_pair_traverse_some(
    const Bvh<N>& a,
    const ClassMasks& masks_a,
    const Bvh<N>& b,
    const ClassMasks& masks_b,
    std::span<const Dop<N>> triangle_bounds,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs);

}  // namespace skelcd::culling
