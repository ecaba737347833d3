#pragma once
// Bounded memory (docs/culling.md "Bounded memory"): one query's triangle pairs go through the
// feature stage and the elementary tests a block at a time, so that what is held at once (the
// pairs, their feature candidates, the tests' outcomes) is bounded by the block size whatever the
// motion. A producer — a traversal in installments (drain) or one that pushes pairs as it goes and
// asks flush_if_full — fills the block; every method with a traversal shares this one loop.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// What a block of `block_pairs` may hold, to reserve up front: the block, passed by at most one
/// bucket pair's pairs (bucket_size(leaf_size)², culling/bvh.hpp; a leaf pair's, leaf_size², is
/// no more), and never more than a first guess of a whole query's (16 per triangle) when the
/// block is larger than that.
[[nodiscard]] inline std::size_t block_reserve(
    std::size_t block_pairs, std::int32_t leaf_size, std::int32_t num_triangles) {
  const auto bucket = static_cast<std::size_t>(bucket_size(leaf_size));
  return std::min(block_pairs, 16 * static_cast<std::size_t>(num_triangles)) + bucket * bucket;
}

/// The stages of one query, a block of at most about `block_pairs` triangle pairs at a time.
/// start_ccd / start_dcd bind the query; producers append to pairs(); finish() tests what is left
/// and sorts the query's findings. Blocks never repeat a test (the CCD feature de-duplication is
/// by ownership within each triangle pair; DCD tests triangle pairs themselves), and the findings
/// are sorted canonically at the end, so the output does not depend on where blocks are cut.
/// @note Allocation-free once its vectors have reached the sizes an earlier query needed.
template <int N>
class PairBlocks {
 public:
  /// @param block_pairs triangle pairs per block (MethodOptions::block_pairs), ≥ 1.
  /// @param reserve_pairs capacity reserved up front for the pairs (a block, plus a bucket
  /// pair's: block_reserve).
  explicit PairBlocks(std::size_t block_pairs = kCcdBlockPairs, std::size_t reserve_pairs = 0);

  /// Starts a CCD query over x_t0 → x_t1: each block → ccd_candidates_from_triangle_pairs (volumes
  /// `bounds`) → run_ccd_tests into `out`. Pairs may come in either order within a pair.
  /// The references must outlive the query (until finish()).
  void start_ccd(
      const FeatureTopology& topology,
      const FeatureBounds<N>& bounds,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1,
      const ElementaryTests& tests,
      ccd::Accuracy accuracy,
      const ccd::CcdOptions& options,
      FrameResult& out);

  /// Starts a DCD query at x: each block → (a, b) ordered → filter_and_run_dcd_tests (the DCD
  /// filter and the tests in one pass) into `out`, with the vertex fans certified once here, and
  /// the triangles' planes computed once at the first block when it holds at least
  /// min(block_pairs, #triangles) pairs (the planes change no answer, only the time).
  void start_dcd(
      const FeatureTopology& topology,
      const skinning::Positions& x,
      const ElementaryTests& tests,
      FrameResult& out);

  /// The DCD query's certified vertex fans (empty when the tests do not use them): what a
  /// FanSieve of the producer may settle pairs with.
  [[nodiscard]] std::span<const std::uint8_t> fans() const { return fans_; }

  /// CCD: decides every vertex's fan over the query's interval now (they are otherwise decided
  /// when a pair first shares the vertex) and returns them as a FanSieve wants them (1 where
  /// certified); empty when the query does not use fans (ccd_uses_fans). Valid until the next
  /// query.
  std::span<const std::uint8_t> certify_interval_fans();

  /// The pending block: producers append here.
  [[nodiscard]] std::vector<TrianglePair>& pairs() { return pairs_; }
  [[nodiscard]] std::size_t block_pairs() const { return block_pairs_; }
  [[nodiscard]] bool full() const { return pairs_.size() >= block_pairs_; }

  /// Tests the pending pairs (if any) and empties the block.
  void flush();
  void flush_if_full() {
    if (full()) flush();
  }

  /// Runs a traversal in installments: `step(pairs, max_pairs)` appends pairs until pairs holds
  /// at least max_pairs (self_traverse_some, pair_traverse_some) and returns true when the
  /// traversal is done; each full block is tested before the next installment. A partial last
  /// block stays pending for the next producer or finish().
  template <class Step>
  void drain(Step&& step) {
    for (bool done = false; !done;) {
      done = step(pairs_, block_pairs_);
      flush_if_full();
    }
  }

  /// drain, with each full block tested while `step` produces the next installment on another
  /// thread when the tests have threads (ElementaryTests::threads > 1, which the runner gives a
  /// query only when it checks no other one at the time: docs/check.md "Threads"). The blocks,
  /// their order and so every finding and counter are drain's; only the time changes. At most two
  /// blocks of pairs are held (the one tested, the one filling). `step` runs beside the tests, so
  /// it may write to the findings' counters only `bv_tests` and read none of the findings or
  /// counters that the tests write; what the tests kept so far is candidates_kept(). On one
  /// thread it is drain, allocation-free as drain is.
  template <class Step>
  void drain_overlapped(Step&& step) {
    if (tests_->threads <= 1) {
      drain(step);
      return;
    }
    using Callable = std::remove_reference_t<Step>;
    drain_beside(Installment{
        const_cast<void*>(static_cast<const void*>(&step)),
        [](void* f, std::vector<TrianglePair>& pairs, std::size_t max_pairs) {
          return (*static_cast<Callable*>(f))(pairs, max_pairs);
        }});
  }

  /// Triangle pairs the feature stage kept (CCD candidate pairs) in the blocks of this query
  /// tested before the current installment began: readable by an installment of
  /// drain_overlapped.
  [[nodiscard]] std::int64_t candidates_kept() const { return kept_visible_; }

  /// Tests what is pending, then sorts the findings appended since start_* canonically (contacts
  /// by (kind, a, b), DCD pairs by (a, b)) in place. Ends the query.
  void finish();
  /// Frees the triangles' planes a DCD query keeps for the next one (#F × 48 bytes), between
  /// queries: for a holder whose DCD queries are rare (clustering::RadialViewMethod's start DCD).
  void release_dcd_planes() {
    std::vector<ccd::TrianglePlane>().swap(planes_);
    use_planes_ = false;
  }

  /// Blocks tested in this query (at least 1 once anything was tested).
  [[nodiscard]] std::int64_t blocks() const { return blocks_; }
  /// µs of this query spent in the feature stage (CCD; DCD only orders its pairs) and in the
  /// elementary tests (DCD: the filter and the triangle tests, filter_and_run_dcd_tests).
  [[nodiscard]] double feature_us() const { return feature_us_; }
  [[nodiscard]] double test_us() const { return test_us_; }

 private:
  void start(const FeatureTopology& topology, const ElementaryTests& tests, FrameResult& out);
  /// A producer of drain_overlapped, not owned (no allocation to pass it).
  struct Installment {
    void* step;
    bool (*call)(void* step, std::vector<TrianglePair>& pairs, std::size_t max_pairs);
    bool operator()(std::vector<TrianglePair>& pairs, std::size_t max_pairs) const {
      return call(step, pairs, max_pairs);
    }
  };
  /// drain_overlapped with threads for the tests.
  void drain_beside(Installment step);
  /// flush() of `block` (pairs_, or spare_ while drain_overlapped fills pairs_).
  void flush_block(std::vector<TrianglePair>& block);

  std::size_t block_pairs_;
  std::vector<TrianglePair> pairs_;
  std::vector<TrianglePair> spare_;  ///< drain_overlapped: the block being tested (empty otherwise)
  FeatureCandidates features_;
  // The query being run (null between queries).
  const FeatureTopology* topology_ = nullptr;
  const ElementaryTests* tests_ = nullptr;
  FrameResult* out_ = nullptr;
  bool continuous_ = false;
  const FeatureBounds<N>* bounds_ = nullptr;
  const skinning::Positions* x_t0_ = nullptr;
  const skinning::Positions* x_t1_ = nullptr;
  IntervalEnds ends_;       ///< what the feature stage tests at both ends (CCD)
  PackedEnds packed_ends_;  ///< both ends packed for it, when it reads them so
  ccd::Accuracy accuracy_ = ccd::Accuracy::conservative;
  const ccd::CcdOptions* ccd_options_ = nullptr;
  std::span<const std::uint8_t> fans_;
  bool use_fans_ = false;                     ///< CCD: ccd_uses_fans for this query
  IntervalFans interval_fans_;                ///< CCD: the query's fans, decided on demand
  std::vector<std::uint8_t> interval_flags_;  ///< CCD: certify_interval_fans' flags
  std::vector<ccd::TrianglePlane> planes_;  ///< the DCD instant's (dcd_planes); kept across queries
  bool use_planes_ = false;  ///< planes_ holds this instant's planes (the first block decides)
  std::size_t first_ = 0;    ///< out's findings before this query
  std::int64_t blocks_ = 0;
  std::int64_t candidates_at_start_ = 0;  ///< out.counters.candidate_pairs at start_*
  /// Candidate pairs this query's tested blocks kept, as of the current installment's start
  /// (updated after each block, between rounds while drain_overlapped runs).
  std::int64_t kept_visible_ = 0;
  bool overlapping_ = false;  ///< drain_overlapped is running
  double feature_us_ = 0.0;
  double test_us_ = 0.0;
};

}  // namespace skelcd::culling
