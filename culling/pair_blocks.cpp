#include "culling/pair_blocks.hpp"

#include <tbb/task_group.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <utility>

#include "ccd/after_swept_aabbs.hpp"
#include "culling/pair_sort.hpp"

namespace skelcd::culling {
namespace {

using Clock = std::chrono::steady_clock;

double micros(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::micro>(to - from).count();
}

// Every feature pair of ccd_candidates_from_triangle_pairs passed the volume filter with the
// swept volumes of the interval (vertex_bounds.hpp: on the coordinate axes of Aabb and Kdop16 the
// positions' own min / max, grown by min_separation / 2) or, for Aabb without a contact
// distance, the test of its features' boxes at both ends, which passes only where the swept boxes
// overlap (boxes that miss each other on an axis are apart there at both ends). With
// min_separation 0 those are exactly the swept AABBs the ccd/ kernels test first, and they
// overlap: the kernels may skip that stage (ccd/after_swept_aabbs.hpp, which checks the distance
// and accuracy; the results are the same). Substituted tests are left alone.
ElementaryTests after_swept_aabbs(ElementaryTests tests) {
  if (tests.vertex_face == static_cast<ElementaryTests::VertexFaceFn>(&ccd::vertex_face_ccd)) {
    tests.vertex_face = &ccd::vertex_face_ccd_after_swept_aabbs;
  }
  if (tests.edge_edge == static_cast<ElementaryTests::EdgeEdgeFn>(&ccd::edge_edge_ccd)) {
    tests.edge_edge = &ccd::edge_edge_ccd_after_swept_aabbs;
  }
  return tests;
}

}  // namespace

template <int N>
PairBlocks<N>::PairBlocks(std::size_t block_pairs, std::size_t reserve_pairs)
    : block_pairs_(std::max<std::size_t>(1, block_pairs)) {
  pairs_.reserve(reserve_pairs);
  // A triangle pair yields at most 6 VF and 9 EE candidates; most yield a few.
  features_.vf.reserve(2 * reserve_pairs);
  features_.ee.reserve(2 * reserve_pairs);
}

template <int N>
void PairBlocks<N>::start(
    const FeatureTopology& topology, const ElementaryTests& tests, FrameResult& out) {
  topology_ = &topology;
  tests_ = &tests;
  out_ = &out;
  pairs_.clear();
  blocks_ = 0;
  candidates_at_start_ = out.counters.candidate_pairs;
  kept_visible_ = 0;
  feature_us_ = 0.0;
  test_us_ = 0.0;
}

template <int N>
void PairBlocks<N>::start_ccd(
    const FeatureTopology& topology,
    const FeatureBounds<N>& bounds,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const ElementaryTests& tests,
    ccd::Accuracy accuracy,
    const ccd::CcdOptions& options,
    FrameResult& out) {
  start(topology, tests, out);
  continuous_ = true;
  bounds_ = &bounds;
  x_t0_ = &x_t0;
  x_t1_ = &x_t1;
  accuracy_ = accuracy;
  ccd_options_ = &options;
  first_ = out.contacts.size();
  // Vertex fans over the interval settle triangle pairs that share a certified corner
  // (ccd_uses_fans says when), each decided when a pair first shares it: a query may have few.
  use_fans_ = ccd_uses_fans(topology, tests, options);
  if (use_fans_) interval_fans_.start(topology.fans(), x_t0, x_t1, topology.num_vertices());
  // The positions at both ends, and packed for the feature stage when it reads them so.
  ends_ = interval_ends(options.min_separation, x_t0, x_t1);
  if (ends_.x_t0 != nullptr && topology.num_triangles() >= kPackedEndsFrom &&
      feature_stage_reads_packed_ends()) {
    packed_ends_.pack(x_t0, x_t1);
    ends_.packed = packed_ends_.data();
  }
}

template <int N>
void PairBlocks<N>::start_dcd(
    const FeatureTopology& topology,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    FrameResult& out) {
  start(topology, tests, out);
  continuous_ = false;
  x_t0_ = &x;
  x_t1_ = &x;
  first_ = out.dcd_pairs.size();
  // Once per instant, for every block (valid until this thread's next certify_dcd_fans).
  const auto t0 = Clock::now();
  fans_ = certify_dcd_fans(topology, x, tests);
  test_us_ += micros(t0, Clock::now());
  use_planes_ = false;
}

template <int N>
std::span<const std::uint8_t> PairBlocks<N>::certify_interval_fans() {
  assert(out_ != nullptr && continuous_);
  if (!use_fans_) return {};
  interval_fans_.certify_all(interval_flags_);
  return interval_flags_;
}

template <int N>
void PairBlocks<N>::flush() {
  flush_block(pairs_);
}

template <int N>
void PairBlocks<N>::drain_beside(Installment step) {
  assert(out_ != nullptr);
  for (bool done = false; !done;) {
    if (!full()) {
      done = step(pairs_, block_pairs_);
      continue;
    }
    // The full block is tested here while another thread fills the next one: `step` then
    // appends to an empty block, as it would after drain's flush.
    if (spare_.capacity() < pairs_.capacity()) spare_.reserve(pairs_.capacity());
    std::swap(pairs_, spare_);
    overlapping_ = true;
    bool next_done = false;
    tbb::task_group group;
    group.run([&] { next_done = step(pairs_, block_pairs_); });
    try {
      flush_block(spare_);
    } catch (...) {
      // The installment reads what the tests hold: it ends before they go.
      try {
        group.wait();
      } catch (...) {  // NOLINT(bugprone-empty-catch): the tests' exception is the one reported
      }
      overlapping_ = false;
      throw;
    }
    group.wait();  // rethrows the installment's exception
    overlapping_ = false;
    kept_visible_ = out_->counters.candidate_pairs - candidates_at_start_;
    done = next_done;
  }
  flush_if_full();
}

template <int N>
void PairBlocks<N>::flush_block(std::vector<TrianglePair>& block) {
  assert(out_ != nullptr);
  if (block.empty()) return;
  FrameResult& out = *out_;
  const auto t0 = Clock::now();
  if (continuous_) {
    features_.clear();
    ccd_candidates_from_triangle_pairs<N>(
        *topology_,
        block,
        *bounds_,
        features_,
        out.counters,
        use_fans_ ? &interval_fans_ : nullptr,
        ends_);
    const auto t1 = Clock::now();
    run_ccd_tests(
        *topology_,
        features_,
        *x_t0_,
        *x_t1_,
        after_swept_aabbs(*tests_),
        accuracy_,
        *ccd_options_,
        out,
        ContactOrder::as_tested);  // sorted once, by finish()
    feature_us_ += micros(t0, t1);
    test_us_ += micros(t1, Clock::now());
  } else {
    // Pairs across two hierarchies come as (triangle of a, triangle of b): DCD wants a < b.
    for (auto& p : block) {
      if (p.b < p.a) std::swap(p.a, p.b);
    }
    const auto t1 = Clock::now();
    if (blocks_ == 0) {
      // The query's first block decides. Every triangle's plane costs about what a few tests
      // save: worth it when this instant tests about as many pairs as there are triangles (a
      // first block that is full, or as long), not for a query that tests a few pairs (CesiumMan:
      // ~2,500 tests, 4,300 triangles).
      use_planes_ = block.size() >=
                    std::min(block_pairs_, static_cast<std::size_t>(topology_->num_triangles()));
      if (use_planes_) dcd_planes(*topology_, *x_t0_, *tests_, planes_);
    }
    filter_and_run_dcd_tests(
        *topology_,
        block,
        *x_t0_,
        *tests_,
        fans_,
        use_planes_ ? std::span<const ccd::TrianglePlane>(planes_)
                    : std::span<const ccd::TrianglePlane>{},
        out);
    feature_us_ += micros(t0, t1);
    test_us_ += micros(t1, Clock::now());
  }
  block.clear();
  ++blocks_;
  if (!overlapping_) kept_visible_ = out.counters.candidate_pairs - candidates_at_start_;
}

template <int N>
void PairBlocks<N>::finish() {
  flush();
  FrameResult& out = *out_;
  if (continuous_) {
    // The blocks' contacts, in test order, sorted as one.
    sort_contacts(std::span(out.contacts).subspan(first_));
  } else {
    sort_pairs(std::span(out.dcd_pairs).subspan(first_));
  }
  out_ = nullptr;
  fans_ = {};
}

template class PairBlocks<3>;
template class PairBlocks<8>;

}  // namespace skelcd::culling
