#include "culling/traversal.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "culling/cluster_checks.hpp"
#include "culling/feature_topology.hpp"

namespace skelcd::culling {
namespace {

using Entry = TraversalScratch::Entry;

inline void push(std::vector<Entry>& stack, std::int32_t a, std::int32_t b) {
  // The reserve_* bounds are proven; growing here would mean the proof is wrong.
  assert(stack.size() < stack.capacity());
  stack.push_back({a, b});
}

inline std::size_t to_size(std::int32_t i) { return static_cast<std::size_t>(i); }

/// Set bits of 0..15 (std::popcount is a library call without -mpopcnt).
constexpr std::array<std::int8_t, 16> kBitsIn4{0, 1, 1, 2, 1, 2, 2, 3, 1, 2, 2, 3, 2, 3, 3, 4};

// A slot is one child of a wide node: node · 4 + lane. Stack entries hold two slots; an entry
// whose first slot is negative (~slot) is a leaf pair whose float volumes overlap, put off
// because the installment was full (its exact test and pairs come when it is popped).
constexpr int kWidth = 4;
inline std::int32_t slot(std::int32_t node, int lane) { return node * kWidth + lane; }
inline std::size_t node_of(std::int32_t s) { return to_size(s >> 2); }
inline int lane_of(std::int32_t s) { return s & (kWidth - 1); }

/// Bit i set when child i of `w` (i < w.num_children) overlaps lane `lane` of `q` in float.
template <int N>
inline unsigned overlap_lanes(const WideBvhNode<N>& w, const WideBvhNode<N>& q, int lane) {
  const unsigned used = (1u << w.num_children) - 1u;
#if defined(__SSE2__)
  __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
  for (int k = 0; k < N; ++k) {
    const __m128 q_lo = _mm_set1_ps(q.lo[k][lane]);
    const __m128 q_hi = _mm_set1_ps(q.hi[k][lane]);
    ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_load_ps(w.lo[k]), q_hi));
    ok = _mm_and_ps(ok, _mm_cmple_ps(q_lo, _mm_load_ps(w.hi[k])));
  }
  return static_cast<unsigned>(_mm_movemask_ps(ok)) & used;
#else
  unsigned mask = 0;
  for (int i = 0; i < kWidth; ++i) {
    bool hit = true;
    for (int k = 0; k < N; ++k) {
      hit = hit && w.lo[k][i] <= q.hi[k][lane] && q.lo[k][lane] <= w.hi[k][i];
    }
    mask |= static_cast<unsigned>(hit) << i;
  }
  return mask & used;
#endif
}

}  // namespace

unsigned end_boxes_meet(const WideEndBoxes& w, const WideEndBoxes& q, int lane, unsigned wanted) {
  // Apart on an axis when one lane's box lies strictly below the other's at t = 0 and at t = 1
  // (traversal.hpp says why that holds in between). NaN compares false: such lanes meet.
#if defined(__SSE2__)
  __m128 apart = _mm_setzero_ps();
  for (int k = 0; k < 3; ++k) {
    const __m128 below = _mm_and_ps(
        _mm_cmplt_ps(_mm_load_ps(w.hi0[k]), _mm_set1_ps(q.lo0[k][lane])),
        _mm_cmplt_ps(_mm_load_ps(w.hi1[k]), _mm_set1_ps(q.lo1[k][lane])));
    const __m128 above = _mm_and_ps(
        _mm_cmplt_ps(_mm_set1_ps(q.hi0[k][lane]), _mm_load_ps(w.lo0[k])),
        _mm_cmplt_ps(_mm_set1_ps(q.hi1[k][lane]), _mm_load_ps(w.lo1[k])));
    apart = _mm_or_ps(apart, _mm_or_ps(below, above));
  }
  return ~static_cast<unsigned>(_mm_movemask_ps(apart)) & wanted;
#else
  unsigned mask = 0;
  for (int i = 0; i < kWidth; ++i) {
    bool apart = false;
    for (int k = 0; k < 3; ++k) {
      const bool below = w.hi0[k][i] < q.lo0[k][lane] && w.hi1[k][i] < q.lo1[k][lane];
      const bool above = q.hi0[k][lane] < w.lo0[k][i] && q.hi1[k][lane] < w.lo1[k][i];
      apart = apart || below || above;
    }
    mask |= static_cast<unsigned>(!apart) << i;
  }
  return mask & wanted;
#endif
}

namespace {

/// Bit i set when corner i (0..2) of `a` is a vertex of `b` (corners as in SlotAdjacency::corners;
/// negative ids never match).
inline unsigned shared_lanes(
    const std::array<std::int32_t, 4>& a, const std::array<std::int32_t, 4>& b) {
#if defined(__SSE2__)
  const __m128i va = _mm_loadu_si128(reinterpret_cast<const __m128i*>(a.data()));
  __m128i eq = _mm_cmpeq_epi32(va, _mm_set1_epi32(b[0]));
  eq = _mm_or_si128(eq, _mm_cmpeq_epi32(va, _mm_set1_epi32(b[1])));
  eq = _mm_or_si128(eq, _mm_cmpeq_epi32(va, _mm_set1_epi32(b[2])));
  eq = _mm_and_si128(eq, _mm_cmpgt_epi32(va, _mm_set1_epi32(-1)));
  return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(eq))) & 7u;
#else
  unsigned mask = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const bool hit = a[i] >= 0 && (a[i] == b[0] || a[i] == b[1] || a[i] == b[2]);
    mask |= static_cast<unsigned>(hit) << i;
  }
  return mask;
#endif
}

/// The class masks of a masked walk (culling/cluster_checks.hpp, ClassMasks) of both trees (one
/// tree's twice in a self walk): the binary nodes', read per wide lane through WideBvhNode::node,
/// and the slots', four at a time.
struct WalkMasks {
  const std::uint8_t* node_a = nullptr;
  const std::uint8_t* node_b = nullptr;
  const std::uint8_t* slots_a = nullptr;
  const std::uint8_t* slots_b = nullptr;  // padded: four can be read from any slot
  MaskedPairs which = MaskedPairs::tested;
};

/// Bit c set when the triangle pair of slot masks (mi, slots[c]), c < 4, is one `which` selects:
/// pair_wanted (cluster_checks.hpp) on four slots at once. A pair is skipped when both masks are
/// the same single sign, so with `mi` of no single sign every lane is a tested pair.
inline unsigned wanted_slots(std::uint8_t mi, const std::uint8_t* slots, MaskedPairs which) {
#if defined(__SSE2__)
  if (mi != kMaskPositive && mi != kMaskNegative) return which == MaskedPairs::tested ? 0xFu : 0u;
  std::int32_t four = 0;
  std::memcpy(&four, slots, sizeof four);
  const __m128i eq = _mm_cmpeq_epi8(_mm_cvtsi32_si128(four), _mm_set1_epi8(static_cast<char>(mi)));
  const auto same = static_cast<unsigned>(_mm_movemask_epi8(eq)) & 0xFu;
  return which == MaskedPairs::tested ? ~same & 0xFu : same;
#else
  unsigned bits = 0;
  for (unsigned c = 0; c < 4; ++c) {
    bits |= static_cast<unsigned>(pair_wanted(mi, slots[c], which)) << c;
  }
  return bits;
#endif
}

/// One traversal over wide nodes: of one tree with itself (kSelf: a and b are the same tree) or of
/// two trees. Entries on the stack are slot pairs whose float volumes overlap (the first entry
/// excepted: it is the virtual roots, never tested).
/// kSieve: a FanSieve settles pairs instead of emitting them (self traversal only).
/// kMasked: only node pairs that may hold a pair `masks.which` selects are visited
/// (node_pair_wanted on the lanes' masks), only such triangle pairs (pair_wanted) are emitted, each
/// as (smaller id, larger id) in a pair walk too.
template <int N, bool kSelf, bool kSieve = false, bool kMasked = false>
class Walk {
 public:
  Walk(
      const Bvh<N>& a,
      std::span<const Dop<N>> bounds_a,
      const Bvh<N>& b,
      std::span<const Dop<N>> bounds_b,
      std::vector<Entry>& stack,
      std::vector<TrianglePair>& out,
      std::int64_t& bv_tests,
      std::size_t max_pairs,
      FanSieve* sieve = nullptr,
      const WalkMasks& masks = {},
      const RowSkip* rows = nullptr)
      : sieve_(sieve),
        masks_(masks),
        a_(a),
        b_(b),
        wide_a_(a.wide_nodes()),
        wide_b_(b.wide_nodes()),
        order_a_(a.triangle_order()),
        order_b_(b.triangle_order()),
        bounds_a_(bounds_a),
        bounds_b_(bounds_b),
        ends_a_(a.end_boxes()),
        ends_b_(b.end_boxes()),
        relative_(!ends_a_.empty() && !ends_b_.empty()),
        stack_(stack),
        out_(out),
        bv_tests_(bv_tests),
        max_pairs_(max_pairs) {
    for (std::size_t k = 0; k < kAxes; ++k) {
      const auto axis = static_cast<int>(k);
      a_lo_[k] = a.slot_lo(axis);
      a_hi_[k] = a.slot_hi(axis);
      b_lo_[k] = b.slot_lo(axis);
      b_hi_[k] = b.slot_hi(axis);
    }
    whole_ = a.slot_volumes_whole() && b.slot_volumes_whole();
    if (whole_) {
      for (std::size_t k = 0; k < kDiagonals; ++k) {
        const auto axis = static_cast<int>(k);
        da_lo_[k] = a.slot_diagonal_lo(axis);
        da_hi_[k] = a.slot_diagonal_hi(axis);
        db_lo_[k] = b.slot_diagonal_lo(axis);
        db_hi_[k] = b.slot_diagonal_hi(axis);
      }
    }
    slot_ends_ = a.slot_ends(0) != nullptr && b.slot_ends(0) != nullptr;
    if (slot_ends_) {
      for (std::size_t r = 0; r < 12; ++r) {
        ends_rows_a_[r] = a.slot_ends(static_cast<int>(r));
        ends_rows_b_[r] = b.slot_ends(static_cast<int>(r));
      }
    }
    if (rows != nullptr) {
      node_row_ = rows->nodes.data();
      slot_row_ = rows->slots.data();
    }
    if (sieve != nullptr) {
      corners_ = sieve->slots->corners.data();
      window_ = sieve->slots->window.data();
      full_ = sieve->full.data();
      certified_ = sieve->certified.data();
    }
  }

  /// Pairs dropped in the leaves as apart at both ends (slot end boxes), so far.
  [[nodiscard]] std::int64_t apart_at_both_ends() const { return apart_; }

  /// Runs until the stack is empty (true) or `out` holds max_pairs (false).
  bool run() {
    while (!stack_.empty()) {
      if (out_.size() >= max_pairs_) return false;
      const Entry e = stack_.back();
      stack_.pop_back();
      if (e.a < 0) {
        leaf_pairs(~e.a, e.b);
      } else if (kSelf && e.a == e.b) {
        self_slot(e.a);
      } else {
        node_pair(e.a, e.b);
      }
    }
    return true;
  }

 private:
  /// A slot against itself: pairs inside its child. A leaf's own pairs (leaf_size > 1); a wide
  /// node's children each against itself, and each two of them whose volumes overlap.
  void self_slot(std::int32_t s) {
    const WideBvhNode<N>& parent = wide_a_[node_of(s)];
    const std::int32_t c = parent.child[lane_of(s)];
    if (c < 0) {
      if (node_row_ != nullptr && node_row_[to_size(parent.node[lane_of(s)])] >= 0) return;
      if (parent.count[lane_of(s)] > 1) leaf_pairs(s, s);  // popped: the installment has room
      return;
    }
    const WideBvhNode<N>& w = wide_a_[to_size(c)];
    const int m = w.num_children;
    for (int i = 0; i < m; ++i) {
      if (node_row_ != nullptr && node_row_[to_size(w.node[i])] >= 0) continue;  // one rigid row
      if constexpr (kMasked) {
        const std::uint8_t mi = masks_.node_a[to_size(w.node[i])];
        if (!node_pair_wanted(mi, mi, masks_.which)) continue;
      }
      if (w.child[i] >= 0 || w.count[i] > 1) push(stack_, slot(c, i), slot(c, i));
    }
    for (int i = 0; i + 1 < m; ++i) {
      // Children i < j: lanes above i (a masked walk: only those that may hold a wanted pair
      // with i, and none tested when there are none).
      unsigned wanted = ~((2u << i) - 1u);
      if (node_row_ != nullptr) wanted &= ~same_row_lanes(w, node_row_[to_size(w.node[i])]);
      if constexpr (kMasked) {
        wanted &= wanted_children(w, masks_.node_a, masks_.node_a[to_size(w.node[i])]);
        if (wanted == 0) continue;
      }
      unsigned mask = overlap_lanes<N>(w, w, i) & wanted;
      if (relative_ && mask != 0)
        mask = end_boxes_meet(ends_a_[to_size(c)], ends_a_[to_size(c)], i, mask);
      bv_tests_ += m - 1 - i;
      while (mask != 0) {
        const int j = std::countr_zero(mask);
        mask &= mask - 1;
        if (w.child[i] < 0 && w.child[j] < 0) {
          leaf_pair(slot(c, i), slot(c, j));
        } else {
          push(stack_, slot(c, i), slot(c, j));
        }
      }
    }
    push_deferred();
  }

  /// Two slots (of a and of b) whose volumes overlap, not both leaves: the children of the one
  /// with more triangles (a leaf is never split) against the other, four at a time.
  void node_pair(std::int32_t sa, std::int32_t sb) {
    const WideBvhNode<N>& pa = wide_a_[node_of(sa)];
    const WideBvhNode<N>& pb = wide_b_[node_of(sb)];
    const int la = lane_of(sa);
    const int lb = lane_of(sb);
    const std::int32_t ca = pa.child[la];
    const std::int32_t cb = pb.child[lb];
    if (ca < 0 && cb < 0) {
      leaf_pairs(sa, sb);  // the virtual roots of two one-leaf trees (popped: there is room)
      return;
    }
    if (cb < 0 || (ca >= 0 && pa.count[la] >= pb.count[lb])) {
      const WideBvhNode<N>& w = wide_a_[to_size(ca)];
      unsigned mask = overlap_lanes<N>(w, pb, lb);
      if (node_row_ != nullptr) mask &= ~same_row_lanes(w, node_row_[to_size(pb.node[lb])]);
      if constexpr (kMasked) {
        mask &= wanted_children(w, masks_.node_a, masks_.node_b[to_size(pb.node[lb])]);
      }
      if (relative_ && mask != 0) {
        mask = end_boxes_meet(ends_a_[to_size(ca)], ends_b_[node_of(sb)], lb, mask);
      }
      bv_tests_ += w.num_children;
      while (mask != 0) {
        const int i = std::countr_zero(mask);
        mask &= mask - 1;
        if (w.child[i] < 0 && cb < 0) {
          leaf_pair(slot(ca, i), sb);
        } else {
          push(stack_, slot(ca, i), sb);
        }
      }
    } else {
      const WideBvhNode<N>& w = wide_b_[to_size(cb)];
      unsigned mask = overlap_lanes<N>(w, pa, la);
      if (node_row_ != nullptr) mask &= ~same_row_lanes(w, node_row_[to_size(pa.node[la])]);
      if constexpr (kMasked) {
        mask &= wanted_children(w, masks_.node_b, masks_.node_a[to_size(pa.node[la])]);
      }
      if (relative_ && mask != 0) {
        mask = end_boxes_meet(ends_b_[to_size(cb)], ends_a_[node_of(sa)], la, mask);
      }
      bv_tests_ += w.num_children;
      while (mask != 0) {
        const int j = std::countr_zero(mask);
        mask &= mask - 1;
        if (w.child[j] < 0 && ca < 0) {
          leaf_pair(sa, slot(cb, j));
        } else {
          push(stack_, sa, slot(cb, j));
        }
      }
    }
    push_deferred();
  }

  /// Two leaf slots met while splitting an entry: their pairs now, or put off when the
  /// installment is full, so that it passes max_pairs by one bucket pair's pairs at most.
  void leaf_pair(std::int32_t sa, std::int32_t sb) {
    if (out_.size() >= max_pairs_) {
      deferred_[num_deferred_++] = {~sa, sb};
      return;
    }
    leaf_pairs(sa, sb);
  }

  /// Pushes the leaf pairs put off while splitting one entry, last first, so that they are
  /// popped first and in the order met: the pairs come in the order of an uninterrupted run.
  void push_deferred() {
    while (num_deferred_ > 0) {
      const Entry& e = deferred_[--num_deferred_];
      push(stack_, e.a, e.b);
    }
  }

  /// The triangle pairs of two bucket slots (one bucket's own pairs when they are the same),
  /// each tested with the exact double volumes. Everything it reads comes through the pointers
  /// the constructor cached: a store to `out` could otherwise alias the trees' and the sieve's
  /// members, and the compiler would load them again for every four slots.
  void leaf_pairs(std::int32_t sa, std::int32_t sb) {
    const WideBvhNode<N>& pa = wide_a_[node_of(sa)];
    const WideBvhNode<N>& pb = wide_b_[node_of(sb)];
    const std::int32_t begin_a = ~pa.child[lane_of(sa)];
    const std::int32_t end_a = begin_a + pa.count[lane_of(sa)];
    const std::int32_t begin_b = ~pb.child[lane_of(sb)];
    const std::int32_t end_b = begin_b + pb.count[lane_of(sb)];
    const bool same = kSelf && sa == sb;
    std::int64_t tests = 0;
    std::int64_t settled = 0;
#if defined(__SSE2__)
    // Two buckets of at most four: b's four slots are loaded once for all of a's.
    const bool one_group = !same && end_b - begin_b <= kWidth;
    const Group b_group = one_group ? load_group(begin_b) : Group{};
#endif
    // Four slots of a at a time; across two buckets only those within b's bucket box, which holds
    // every slot box of b (one test of four slots instead of four of b's).
    for (std::int32_t i0 = begin_a; i0 < end_a; i0 += kWidth) {
      const std::int32_t m = std::min(kWidth, end_a - i0);
      unsigned a_mask = (1u << m) - 1u;
#if defined(__SSE2__)
      if (!same) {
        a_mask &= group_within_lane(i0, pb, lane_of(sb));
        tests += m;
      }
#endif
      while (a_mask != 0) {
        const std::int32_t i = i0 + std::countr_zero(a_mask);
        a_mask &= a_mask - 1;
        const std::int32_t ti = order_a_[to_size(i)];
        [[maybe_unused]] std::uint8_t mi = 0;
        if constexpr (kMasked) mi = masks_.slots_a[to_size(i)];
        for (std::int32_t j0 = same ? i + 1 : begin_b; j0 < end_b; j0 += kWidth) {
          const std::int32_t n = std::min(kWidth, end_b - j0);
          // Four slots of b at once in float (the slots past the tree's last are empty), which only
          // prunes; then the pairs left, one by one.
#if defined(__SSE2__)
          unsigned mask =
              float_overlap_group(i, one_group ? b_group : load_group(j0)) & ((1u << n) - 1u);
#else
          unsigned mask = float_overlap_slots(i, j0) & ((1u << n) - 1u);
#endif
          tests += n;
          if constexpr (kMasked) mask &= wanted_slots(mi, masks_.slots_b + j0, masks_.which);
          if constexpr (kSieve) {
            // Every corner of slot i certified: its window settles the neighbours it shares a
            // vertex with, four at a time (a pair that shares one overlaps: its bit is in mask).
            const std::int32_t d = j0 - i + SlotAdjacency::kReach;
            if (full_[i] != 0 && d >= 0 && d <= 2 * SlotAdjacency::kReach - 4) {
              const auto window_settled = static_cast<unsigned>(window_[i] >> d) & mask;
              settled += kBitsIn4[window_settled];
              mask &= ~window_settled;
            }
          }
          // Triangles apart on an axis at both ends: the feature stage's first test drops them
          // (candidates.hpp); here four at once, before they are emitted. A pair that shares a
          // vertex never lies apart, so the sieve's count above stays what it was.
          if (slot_ends_ && mask != 0) {
            const unsigned apart = slots_apart_at_both_ends(i, j0) & mask;  // 4 bits
            apart_ += kBitsIn4[apart];
            mask &= ~apart;
          }
          // Whole slot volumes (Bvh::refit_swept): the axes past the first three in floats, four
          // slots at once, instead of the exact volumes by triangle id pair by pair below.
          if constexpr (kDiagonals > 0) {
            if (whole_ && mask != 0) mask &= diagonal_overlap(i, j0);
          }
          while (mask != 0) {
            const std::int32_t sj = j0 + std::countr_zero(mask);
            const std::int32_t tj = order_b_[to_size(sj)];
            mask &= mask - 1;
            if (slot_row_ != nullptr && slot_row_[to_size(i)] >= 0 &&
                slot_row_[to_size(i)] == slot_row_[to_size(sj)]) {
              continue;  // one certified rigid row: its rest pairs are tested instead
            }
            // Two triangles that share a vertex always overlap (both volumes hold it): a settled
            // pair needs no exact volume test.
            if constexpr (kSieve) {
              if (settles(i, sj, ti, tj, settled)) continue;
            }
            // Whole slot volumes held the exact test's axes already (in floats).
            if (!whole_ && !overlap(bounds_a_[to_size(ti)], bounds_b_[to_size(tj)])) continue;
            // Ordered a < b within one tree (a select, not a branch), as given across two (a
            // masked walk's two trees are parts of one mesh: ordered too).
            if constexpr (kSelf || kMasked) {
              out_.push_back({std::min(ti, tj), std::max(ti, tj)});
            } else {
              out_.push_back({ti, tj});
            }
          }
        }
      }
    }
    bv_tests_ += tests;
    if constexpr (kSieve) sieve_->settled += settled;
  }

  /// Bit c set when slot sa of a and slot sb + c of b (c < 4) lie apart on an axis at both ends
  /// of the interval by their end boxes (Bvh::refit_slot_ends): floats rounded outwards, so apart
  /// here is apart in the exact boxes too.
  [[nodiscard]] unsigned slots_apart_at_both_ends(std::int32_t sa, std::int32_t sb) const {
    const auto ia = to_size(sa);
    const auto ib = to_size(sb);
#if defined(__SSE2__)
    __m128 apart = _mm_setzero_ps();
    for (std::size_t k = 0; k < 3; ++k) {
      const __m128 below = _mm_and_ps(
          _mm_cmplt_ps(_mm_set1_ps(ends_rows_a_[3 + k][ia]), _mm_loadu_ps(ends_rows_b_[k] + ib)),
          _mm_cmplt_ps(
              _mm_set1_ps(ends_rows_a_[9 + k][ia]), _mm_loadu_ps(ends_rows_b_[6 + k] + ib)));
      const __m128 above = _mm_and_ps(
          _mm_cmplt_ps(_mm_loadu_ps(ends_rows_b_[3 + k] + ib), _mm_set1_ps(ends_rows_a_[k][ia])),
          _mm_cmplt_ps(
              _mm_loadu_ps(ends_rows_b_[9 + k] + ib), _mm_set1_ps(ends_rows_a_[6 + k][ia])));
      apart = _mm_or_ps(apart, _mm_or_ps(below, above));
    }
    return static_cast<unsigned>(_mm_movemask_ps(apart));
#else
    const auto& a = ends_rows_a_;
    const auto& b = ends_rows_b_;
    unsigned bits = 0;
    for (std::size_t c = 0; c < 4; ++c) {
      const std::size_t j = ib + c;
      bool apart = false;
      for (std::size_t k = 0; k < 3; ++k) {
        apart = apart || (a[3 + k][ia] < b[k][j] && a[9 + k][ia] < b[6 + k][j]) ||
                (b[3 + k][j] < a[k][ia] && b[9 + k][j] < a[6 + k][ia]);
      }
      bits |= static_cast<unsigned>(apart) << c;
    }
    return bits;
#endif
  }

  /// Bit i set when child i of `w` has the rigid row `row` ≥ 0 (none when row < 0): a pair of it
  /// and a node of that row holds no pair to emit.
  [[nodiscard]] unsigned same_row_lanes(const WideBvhNode<N>& w, std::int32_t row) const {
    if (row < 0) return 0;
    unsigned bits = 0;
    for (int i = 0; i < w.num_children; ++i) {
      bits |= static_cast<unsigned>(node_row_[to_size(w.node[i])] == row) << i;
    }
    return bits;
  }

  /// Bit i set when child i of `w` (node masks `node_masks`) and a node with mask `other` may hold
  /// a wanted pair.
  [[nodiscard]] unsigned wanted_children(
      const WideBvhNode<N>& w, const std::uint8_t* node_masks, std::uint8_t other) const {
    unsigned bits = 0;
    for (int i = 0; i < w.num_children; ++i) {
      bits |= static_cast<unsigned>(
                  node_pair_wanted(node_masks[to_size(w.node[i])], other, masks_.which))
              << i;
    }
    return bits;
  }

  static constexpr int kSlotAxes = Bvh<N>::kSlotAxes;
  static constexpr auto kAxes = static_cast<std::size_t>(kSlotAxes);
  static constexpr auto kDiagonals = static_cast<std::size_t>(Bvh<N>::kSlotDiagonals);

#if defined(__SSE2__)
  /// The float volumes of four consecutive slots of b, by axis.
  struct Group {
    __m128 lo[kAxes];
    __m128 hi[kAxes];
  };

  /// Slots sb … sb + 3 of b.
  [[nodiscard]] Group load_group(std::int32_t sb) const {
    Group g{};
    for (std::size_t k = 0; k < kAxes; ++k) {
      g.lo[k] = _mm_loadu_ps(b_lo_[k] + sb);
      g.hi[k] = _mm_loadu_ps(b_hi_[k] + sb);
    }
    return g;
  }

  /// Bit c set when the float volume of slot sa + c of a (c < 4) overlaps lane `lane` of b's wide
  /// node `w` on the slot axes.
  [[nodiscard]] unsigned group_within_lane(
      std::int32_t sa, const WideBvhNode<N>& w, int lane) const {
    __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
    const auto l = static_cast<std::size_t>(lane);
    for (std::size_t k = 0; k < kAxes; ++k) {
      ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_loadu_ps(a_lo_[k] + sa), _mm_set1_ps(w.hi[k][l])));
      ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_set1_ps(w.lo[k][l]), _mm_loadu_ps(a_hi_[k] + sa)));
    }
    return static_cast<unsigned>(_mm_movemask_ps(ok));
  }

  /// Bit c set when the float volume of slot si of a overlaps lane c of a group of b's slots.
  [[nodiscard]] unsigned float_overlap_group(std::int32_t si, const Group& g) const {
    __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (std::size_t k = 0; k < kAxes; ++k) {
      ok = _mm_and_ps(ok, _mm_cmple_ps(g.lo[k], _mm_set1_ps(a_hi_[k][si])));
      ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_set1_ps(a_lo_[k][si]), g.hi[k]));
    }
    return static_cast<unsigned>(_mm_movemask_ps(ok));
  }
#endif

  /// Bit c set when slot sa of a and slot sb + c of b (c < 4) overlap on the K axes whose rows
  /// of slot floats are given (lo and hi of a, then of b).
  template <std::size_t K>
  [[nodiscard]] static unsigned rows_overlap(
      const std::array<const float*, K>& a_lo,
      const std::array<const float*, K>& a_hi,
      const std::array<const float*, K>& b_lo,
      const std::array<const float*, K>& b_hi,
      std::int32_t sa,
      std::int32_t sb) {
#if defined(__SSE2__)
    __m128 ok = _mm_castsi128_ps(_mm_set1_epi32(-1));
    for (std::size_t k = 0; k < K; ++k) {
      ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_loadu_ps(b_lo[k] + sb), _mm_set1_ps(a_hi[k][sa])));
      ok = _mm_and_ps(ok, _mm_cmple_ps(_mm_set1_ps(a_lo[k][sa]), _mm_loadu_ps(b_hi[k] + sb)));
    }
    return static_cast<unsigned>(_mm_movemask_ps(ok));
#else
    unsigned mask = 0;
    for (int c = 0; c < kWidth; ++c) {
      bool hit = true;
      for (std::size_t k = 0; k < K; ++k) {
        hit = hit && b_lo[k][sb + c] <= a_hi[k][sa] && a_lo[k][sa] <= b_hi[k][sb + c];
      }
      mask |= static_cast<unsigned>(hit) << c;
    }
    return mask;
#endif
  }

#if !defined(__SSE2__)
  /// Bit c set when the float volume of slot si of a overlaps that of slot sb + c of b, c < 4.
  [[nodiscard]] unsigned float_overlap_slots(std::int32_t si, std::int32_t sb) const {
    return rows_overlap(a_lo_, a_hi_, b_lo_, b_hi_, si, sb);
  }
#endif

  /// Bit c set when slot sa of a and slot sb + c of b (c < 4) overlap on the diagonal axes of
  /// their whole slot volumes (Bvh::slot_diagonal_lo): floats rounded outwards, so apart here is
  /// apart in the exact volumes too.
  [[nodiscard]] unsigned diagonal_overlap(std::int32_t sa, std::int32_t sb) const {
    return rows_overlap(da_lo_, da_hi_, db_lo_, db_hi_, sa, sb);
  }

  /// The exact (double) volume test of a triangle pair.
  [[nodiscard]] static bool overlap(const Dop<N>& a, const Dop<N>& b) {
    constexpr auto kN = static_cast<std::size_t>(N);
    std::size_t k = 0;
    bool ok = true;
#if defined(__SSE2__)
    // Two axes a compare (cmplepd is false on NaN, as <= is), an odd last axis alone.
    __m128d both = _mm_castsi128_pd(_mm_set1_epi32(-1));
    for (; k + 2 <= kN; k += 2) {
      const __m128d below = _mm_cmple_pd(_mm_loadu_pd(&a.lo[k]), _mm_loadu_pd(&b.hi[k]));
      const __m128d above = _mm_cmple_pd(_mm_loadu_pd(&b.lo[k]), _mm_loadu_pd(&a.hi[k]));
      both = _mm_and_pd(both, _mm_and_pd(below, above));
    }
    ok = _mm_movemask_pd(both) == 3;
#endif
    for (; k < kN; ++k) ok = ok & (a.lo[k] <= b.hi[k]) & (b.lo[k] <= a.hi[k]);
    return ok;
  }

  /// The pair of slots (si, sj) holding (ti, tj) shares a certified vertex (and not three
  /// vertices): count it in `settled` unless its parts are excluded, and drop it.
  bool settles(
      std::int32_t si, std::int32_t sj, std::int32_t ti, std::int32_t tj, std::int64_t& settled) {
    const auto& ci = corners_[si];
    const unsigned shared = shared_lanes(ci, corners_[sj]);
    if (shared == 0 || shared == 7u) return false;
    for (unsigned m = shared; m != 0; m &= m - 1) {
      if (certified_[ci[static_cast<std::size_t>(std::countr_zero(m))]] != 0) {
        if (!sieve_->topology->triangles_excluded(std::min(ti, tj), std::max(ti, tj))) {
          ++settled;
        }
        return true;
      }
    }
    return false;
  }

  FanSieve* sieve_;
  WalkMasks masks_;
  const Bvh<N>& a_;
  const Bvh<N>& b_;
  std::span<const WideBvhNode<N>> wide_a_;
  std::span<const WideBvhNode<N>> wide_b_;
  std::span<const std::int32_t> order_a_;
  std::span<const std::int32_t> order_b_;
  std::span<const Dop<N>> bounds_a_;
  std::span<const Dop<N>> bounds_b_;
  // The wide nodes' end boxes when both trees have them for this interval: node pairs are then
  // also tested in the relative motion (end_boxes_meet).
  std::span<const WideEndBoxes> ends_a_;
  std::span<const WideEndBoxes> ends_b_;
  bool relative_;
  std::vector<Entry>& stack_;
  std::vector<TrianglePair>& out_;
  std::int64_t& bv_tests_;
  std::size_t max_pairs_;
  std::array<Entry, 6> deferred_{};  // at most one per pair of four children
  std::size_t num_deferred_ = 0;
  // Cached for leaf_pairs: the slots' float volumes of both trees by axis, and the sieve's arrays.
  std::array<const float*, kAxes> a_lo_{};
  std::array<const float*, kAxes> a_hi_{};
  std::array<const float*, kAxes> b_lo_{};
  std::array<const float*, kAxes> b_hi_{};
  // Both trees' slot volumes whole (Bvh::refit_swept): their diagonal axes, and no exact test.
  bool whole_ = false;
  std::array<const float*, kDiagonals> da_lo_{};
  std::array<const float*, kDiagonals> da_hi_{};
  std::array<const float*, kDiagonals> db_lo_{};
  std::array<const float*, kDiagonals> db_hi_{};
  // The slots' end boxes of both trees (Bvh::refit_slot_ends), when both have them.
  bool slot_ends_ = false;
  std::int64_t apart_ = 0;
  std::array<const float*, 12> ends_rows_a_{};
  std::array<const float*, 12> ends_rows_b_{};
  const std::array<std::int32_t, 4>* corners_ = nullptr;
  const std::uint64_t* window_ = nullptr;
  const std::uint8_t* full_ = nullptr;
  const std::uint8_t* certified_ = nullptr;
  // RowSkip's rows (self walks only), null when none.
  const std::int32_t* node_row_ = nullptr;
  const std::int32_t* slot_row_ = nullptr;
};

}  // namespace

template <int N>
bool row_skip(
    const Bvh<N>& bvh,
    std::span<const std::int32_t> triangle_row,
    std::span<const std::uint8_t> certified,
    RowSkip& out) {
  const auto order = bvh.triangle_order();
  const auto nodes = bvh.nodes();
  out.slots.resize(order.size());
  for (std::size_t s = 0; s < order.size(); ++s) {
    const std::int32_t r = triangle_row[to_size(order[s])];
    out.slots[s] = r >= 0 && certified[to_size(r)] != 0 ? r : -1;
  }
  out.nodes.resize(nodes.size());
  bool any = false;
  // Children follow their parent in depth-first order: one backward sweep is bottom-up.
  for (std::size_t n = nodes.size(); n-- > 0;) {
    const BvhNode& node = nodes[n];
    std::int32_t r = -1;
    if (node.is_leaf()) {
      r = node.end > node.begin ? out.slots[to_size(node.begin)] : -1;
      for (std::int32_t s = node.begin + 1; s < node.end && r >= 0; ++s) {
        if (out.slots[to_size(s)] != r) r = -1;
      }
    } else {
      r = out.nodes[n + 1] == out.nodes[to_size(node.right)] ? out.nodes[n + 1] : -1;
    }
    out.nodes[n] = r;
    any = any || r >= 0;
  }
  return any;
}

template <int N>
void start_self_traversal(const Bvh<N>& bvh, TraversalScratch& scratch) {
  scratch.reserve_self(bvh);
  scratch.stack.clear();
  if (!bvh.empty()) push(scratch.stack, 0, 0);  // the virtual root's one child against itself
}

namespace {

/// One installment of a self walk, with the fan sieve compiled in or out (`kSieve`).
template <int N, bool kSieve>
bool self_walk_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs,
    FanSieve* sieve,
    const RowSkip* rows) {
  Walk<N, true, kSieve> walk(
      bvh,
      triangle_bounds,
      bvh,
      triangle_bounds,
      scratch.stack,
      out,
      bv_tests,
      max_pairs,
      sieve,
      {},
      rows);
  const bool done = walk.run();
  scratch.apart_at_both_ends += walk.apart_at_both_ends();
  return done;
}

}  // namespace

template <int N>
bool self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs,
    FanSieve* sieve,
    const RowSkip* rows) {
  if (bvh.empty()) return true;
  if (sieve == nullptr || sieve->certified.empty()) {
    return self_walk_some<N, false>(
        bvh, triangle_bounds, scratch, out, bv_tests, max_pairs, nullptr, rows);
  }
  assert(sieve->slots != nullptr && sieve->topology != nullptr);
  assert(sieve->slots->corners.size() == bvh.triangle_order().size());
  assert(sieve->full.size() == sieve->slots->corners.size());
  return self_walk_some<N, true>(
      bvh, triangle_bounds, scratch, out, bv_tests, max_pairs, sieve, rows);
}

SlotAdjacency::SlotAdjacency(const FeatureTopology& topology, std::span<const std::int32_t> order)
    : corners(order.size()), window(order.size(), 0) {
  for (std::size_t s = 0; s < order.size(); ++s) {
    const auto& t = topology.triangle(order[s]);
    const bool degenerate = t[0] == t[1] || t[1] == t[2] || t[0] == t[2];
    corners[s] = degenerate ? std::array<std::int32_t, 4>{-1, -1, -1, -1}
                            : std::array<std::int32_t, 4>{t[0], t[1], t[2], -1};
  }
  // The slots at each vertex (CSR, ascending): a slot's window bits are among the slots around its
  // corners, a dozen or so, instead of all 2·kReach slots around it (the old loop, which tested
  // each of those: a tenth of a check's start on the characters). Degenerate slots have no
  // corners: no bits, as there.
  const auto num_vertices = static_cast<std::size_t>(std::max(topology.num_vertices(), 0));
  std::vector<std::int32_t> offsets(num_vertices + 1, 0);
  for (const auto& c : corners) {
    for (std::size_t k = 0; k < 3; ++k) {
      if (c[k] >= 0) ++offsets[to_size(c[k]) + 1];
    }
  }
  for (std::size_t v = 0; v < num_vertices; ++v) offsets[v + 1] += offsets[v];
  std::vector<std::int32_t> at_vertex(to_size(offsets[num_vertices]));
  std::vector<std::int32_t> fill(offsets.begin(), offsets.end() - 1);
  const auto n = static_cast<std::int32_t>(order.size());
  for (std::int32_t s = 0; s < n; ++s) {
    for (std::size_t k = 0; k < 3; ++k) {
      const std::int32_t v = corners[to_size(s)][k];
      if (v >= 0) at_vertex[to_size(fill[to_size(v)]++)] = s;
    }
  }
  for (std::int32_t s = 0; s < n; ++s) {
    const auto& c = corners[to_size(s)];
    for (std::size_t k = 0; k < 3; ++k) {
      if (c[k] < 0) continue;
      const auto begin = at_vertex.begin() + offsets[to_size(c[k])];
      const auto end = at_vertex.begin() + offsets[to_size(c[k]) + 1];
      // The slots o in [s − kReach, s + kReach) at this corner, o ≠ s.
      for (auto it = std::lower_bound(begin, end, s - kReach); it != end && *it < s + kReach;
           ++it) {
        const std::int32_t o = *it;
        const std::int32_t d = o - s + kReach;
        if (o == s || ((window[to_size(s)] >> d) & 1u) != 0) continue;
        // Sharing all three vertices (a duplicate face) is not settled.
        if (shared_lanes(c, corners[to_size(o)]) == 7u) continue;
        if (topology.triangles_excluded(order[to_size(s)], order[to_size(o)])) continue;
        window[to_size(s)] |= std::uint64_t{1} << d;
      }
    }
  }
}

void certified_slots(
    const SlotAdjacency& slots,
    std::span<const std::uint8_t> certified,
    std::vector<std::uint8_t>& full) {
  full.resize(slots.corners.size());
  for (std::size_t s = 0; s < full.size(); ++s) {
    const auto& c = slots.corners[s];
    full[s] = static_cast<std::uint8_t>(
        c[0] >= 0 && certified[to_size(c[0])] != 0 && certified[to_size(c[1])] != 0 &&
        certified[to_size(c[2])] != 0);
  }
}

FanSieve fan_sieve(
    const SlotAdjacency& slots,
    std::span<const std::uint8_t> certified,
    std::vector<std::uint8_t>& full,
    const FeatureTopology& topology) {
  FanSieve sieve{.slots = &slots, .certified = certified, .full = {}, .topology = &topology};
  if (!certified.empty()) {
    certified_slots(slots, certified, full);
    sieve.full = full;
  }
  return sieve;
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
  if (!a.empty() && !b.empty()) push(scratch.stack, 0, 0);  // the two virtual roots' children
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
  return Walk<N, false>(
             a, triangle_bounds_a, b, triangle_bounds_b, scratch.stack, out, bv_tests, max_pairs)
      .run();
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

// The masked traversals of culling/cluster_checks.hpp: the same wide walk, with the class masks.
template <int N>
bool masked_self_traverse_some(
    const Bvh<N>& bvh,
    std::span<const Dop<N>> triangle_bounds,
    const ClassMasks& masks,
    MaskedPairs which,
    TraversalScratch& scratch,
    std::vector<TrianglePair>& out,
    std::int64_t& bv_tests,
    std::size_t max_pairs) {
  if (bvh.empty()) return true;
  assert(masks.nodes.size() == bvh.nodes().size());
  assert(masks.slots.size() == bvh.slot_stride());
  const WalkMasks walk_masks{
      masks.nodes.data(), masks.nodes.data(), masks.slots.data(), masks.slots.data(), which};
  return Walk<N, true, false, true>(
             bvh,
             triangle_bounds,
             bvh,
             triangle_bounds,
             scratch.stack,
             out,
             bv_tests,
             max_pairs,
             nullptr,
             walk_masks)
      .run();
}

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
    std::size_t max_pairs) {
  if (a.empty() || b.empty()) return true;
  assert(masks_a.nodes.size() == a.nodes().size() && masks_b.nodes.size() == b.nodes().size());
  assert(masks_a.slots.size() == a.slot_stride());
  assert(masks_b.slots.size() == b.slot_stride());
  const WalkMasks walk_masks{
      masks_a.nodes.data(),
      masks_b.nodes.data(),
      masks_a.slots.data(),
      masks_b.slots.data(),
      which};
  return Walk<N, false, false, true>(
             a,
             triangle_bounds,
             b,
             triangle_bounds,
             scratch.stack,
             out,
             bv_tests,
             max_pairs,
             nullptr,
             walk_masks)
      .run();
}

template void start_self_traversal<3>(const Bvh<3>&, TraversalScratch&);
template void start_self_traversal<8>(const Bvh<8>&, TraversalScratch&);
template bool masked_self_traverse_some<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    const ClassMasks&,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool masked_self_traverse_some<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    const ClassMasks&,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool masked_pair_traverse_some<3>(
    const Bvh<3>&,
    const ClassMasks&,
    const Bvh<3>&,
    const ClassMasks&,
    std::span<const Dop<3>>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool masked_pair_traverse_some<8>(
    const Bvh<8>&,
    const ClassMasks&,
    const Bvh<8>&,
    const ClassMasks&,
    std::span<const Dop<8>>,
    MaskedPairs,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t);
template bool row_skip<3>(
    const Bvh<3>&, std::span<const std::int32_t>, std::span<const std::uint8_t>, RowSkip&);
template bool row_skip<8>(
    const Bvh<8>&, std::span<const std::int32_t>, std::span<const std::uint8_t>, RowSkip&);
template bool self_traverse_some<3>(
    const Bvh<3>&,
    std::span<const Dop<3>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t,
    FanSieve*,
    const RowSkip*);
template bool self_traverse_some<8>(
    const Bvh<8>&,
    std::span<const Dop<8>>,
    TraversalScratch&,
    std::vector<TrianglePair>&,
    std::int64_t&,
    std::size_t,
    FanSieve*,
    const RowSkip*);
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
