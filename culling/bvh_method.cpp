// `bvh` and `kdop`: a hierarchy of AABBs or 16-DOPs over the welded triangles, built once at rest,
// refit per interval, traversed against itself; then the shared feature and elementary stages.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/hierarchy_cache.hpp"
#include "culling/pair_blocks.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/sieved_dcd.hpp"
#include "culling/traversal.hpp"
#include "culling/vertex_bounds.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling::detail {
namespace {

/// Welded rest positions: row w is the rest position of representative_vertex[w].
skinning::Positions welded_rest_positions(
    const skinning::Mesh& mesh, const skinning::Topology& topology) {
  skinning::Positions rest(topology.num_welded_vertices(), 3);
  for (std::int32_t w = 0; w < topology.num_welded_vertices(); ++w) {
    const std::int32_t v = topology.representative_vertex[static_cast<std::size_t>(w)];
    if (v < 0 || v >= mesh.rest_positions.rows()) {
      throw InvalidInput(
          "culling::make_method: representative_vertex[" + std::to_string(w) +
          "] = " + std::to_string(v) + " is not a mesh vertex");
    }
    rest.row(w) = mesh.rest_positions.row(v);
  }
  return rest;
}

/// The hierarchy options of a method that traverses only the wide copy (culling/traversal.hpp):
/// no binary node volumes, 2·#F·sizeof(Dop<N>) bytes less (docs/culling.md "Bounded memory").
BvhOptions traversal_only(BvhOptions options) {
  options.node_volumes = false;
  return options;
}

template <int N>
class BvhMethod final : public MethodBase {
 public:
  BvhMethod(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      bool relative_pairs,
      bool rigid_rows)
      : MethodBase(name, mesh, topology, options),
        relative_pairs_(relative_pairs),
        rigid_rows_(
            rigid_rows && options.rigid_rows != nullptr &&
                    static_cast<std::int64_t>(options.rigid_rows->triangle_row.size()) ==
                        topology.welded_triangles.rows()
                ? options.rigid_rows
                : nullptr),
        tree_(lend_hierarchy<N>(
            options.hierarchies.get(),
            topology_.welded_triangles(),
            welded_rest_positions(mesh, topology),
            traversal_only(options.bvh))) {
    reserve();
  }

  void dcd(const Instant& at, FrameResult& out) override {
    check_positions(at.x, "detect_dcd", "x");
    // Pairs sharing a certified vertex are settled where the traversal finds them (FanSieve).
    sieved_dcd_at<N>(
        at.x, bvh_, bounds_, topology_, *slots_, full_slots_, scratch_, blocks_, tests_, out);
  }

  void ccd(const Interval& interval, FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    check_positions(x_t0, "detect_ccd", "x_t0");
    check_positions(x_t1, "detect_ccd", "x_t1");
    const auto t0 = Clock::now();
    // Refit over the swept volumes of the interval, grown by half the contact distance. No edge
    // volumes: the feature stage forms them from the vertices' (bounded memory). Without a
    // contact distance it reads the positions at both ends instead, and no vertex volumes are
    // held: the triangles' come from their corners directly.
    // Without one, no triangle volumes are held either: the refit computes each from the corners
    // where it rounds it into its slot, on every axis, and the walk tests the floats alone
    // (Bvh::refit_swept; docs/culling.md, "Whole slot volumes").
    const bool ends_tested = feature_stage_tests_ends(options_.min_separation);
    if (ends_tested) {
      bvh_.refit_swept(topology_.welded_triangles(), x_t0, x_t1);
    } else {
      swept_vertex_bounds<N>(x_t0, x_t1, 0.5 * options_.min_separation, bounds_.vertices);
      bounds_.derive(topology_, /*with_edges=*/false);
      bvh_.refit(bounds_.triangles);
    }
    // `kdop`: node pairs tested in the relative motion too when the interval moves enough for it
    // to prune (docs/culling.md "Relative boxes at the nodes").
    const bool node_ends =
        relative_pairs_ && motion_scale(topology_, x_t0, x_t1) >= kNodeRelativeMotion;
    // Without a contact distance the feature stage first drops the triangle pairs apart at both
    // ends (candidates.hpp): the leaves drop them instead, four at a time, before they are
    // emitted (docs/culling.md, "Apart at both ends in the leaves"). The slots' end boxes are
    // built from the start when the last interval saw two such pairs per triangle; within an
    // interval (between two installments of the traversal) once the feature stage has dropped
    // one per two triangles: by then those pairs have cost what the build costs (ski rental:
    // the build takes 40–50 instructions a triangle, a pair the feature stage drops about 140 on
    // the cloth-ball step). Only the time depends on it: the rows are the same either way.
    const std::int64_t pays = kSlotEndsPayPerTriangle * topology_.num_triangles();
    const std::int64_t pays_within = topology_.num_triangles() / 2;
    bool slot_ends = false;
    // The end boxes come from the corners' positions, bounded per triangle (no #W vertex boxes).
    const auto build_slot_ends = [&] {
      bvh_.refit_slot_ends(topology_.welded_triangles(), x_t0, x_t1);
      slot_ends = true;
    };
    if (node_ends) {
      // With the slots' end boxes when they are wanted from the start: the corners gathered once.
      slot_ends = ends_tested && slot_ends_pay_;
      bvh_.refit_end_boxes(
          topology_.welded_triangles(), x_t0, x_t1, 0.5 * options_.min_separation, slot_ends);
    } else if (ends_tested && slot_ends_pay_) {
      build_slot_ends();
    }
    const auto t1 = Clock::now();
    // Self traversal → triangle pairs → de-duplicated feature pairs → tests, in blocks of
    // block_pairs triangle pairs: the candidates held at once stay bounded on any motion (the
    // de-duplication is by ownership within each triangle pair, so blocks never repeat a test).
    blocks_.start_ccd(topology_, bounds_, x_t0, x_t1, tests_, options_.accuracy, ccd_options_, out);
    // Pairs that share a vertex whose fan is certified over the interval have no feature pairs
    // (candidates.hpp): settled where the traversal meets them, as in the DCD, instead of going
    // through the relative filter and the feature stage (not with part exclusions, whose CCD rule
    // is per feature).
    FanSieve sieve = fan_sieve(
        *slots_,
        topology_.has_exclusions() ? std::span<const std::uint8_t>{}
                                   : blocks_.certify_interval_fans(),
        full_slots_,
        topology_);
    FanSieve* const sieving = sieve.certified.empty() ? nullptr : &sieve;
    // Rigid rows (docs/culling.md "Rigid rows"): the pairs of two triangles of one row this
    // interval certifies are skipped in the walk; the row's rest pairs go to the feature stage
    // first instead.
    const RowSkip* const rows = certify_rows(interval);
    std::size_t rest_next = 0;
    start_self_traversal<N>(bvh_, scratch_);
    scratch_.apart_at_both_ends = 0;
    const std::int64_t candidates_before = out.counters.candidate_pairs;
    std::int64_t emitted = 0;
    // `kdop`'s relative pair filter, with a contact distance: without one the feature stage tests
    // the two triangles at both ends first, the same test on the positions (candidates.hpp).
    const bool filter_pairs = relative_pairs_ && !ends_tested;
    if (filter_pairs) relative_.start(RelativePairTrial::trial_pairs(topology_.num_triangles()));
    // With threads to spare the tests of each block run beside the next installment
    // (PairBlocks::drain_overlapped), which reads what they kept through candidates_kept() only.
    blocks_.drain_overlapped([&](std::vector<TrianglePair>& pairs, std::size_t max_pairs) {
      // The pairs so far that the feature stage found apart at both ends.
      if (ends_tested && !slot_ends && emitted - blocks_.candidates_kept() >= pays_within) {
        build_slot_ends();
      }
      const std::size_t first = pairs.size();
      if (rest_next < rest_pairs_.size()) {
        // At most an installment's worth at a time, so that a block stays bounded.
        const std::size_t take = std::min(
            rest_pairs_.size() - rest_next, max_pairs > first ? max_pairs - first : std::size_t{1});
        pairs.insert(
            pairs.end(),
            rest_pairs_.begin() + static_cast<std::ptrdiff_t>(rest_next),
            rest_pairs_.begin() + static_cast<std::ptrdiff_t>(rest_next + take));
        rest_next += take;
      }
      // Rest pairs left over: this installment is full, the walk waits for the next one.
      const bool done = rest_next == rest_pairs_.size() && self_traverse_some<N>(
                                                               bvh_,
                                                               bounds_.triangles,
                                                               scratch_,
                                                               pairs,
                                                               out.counters.bv_tests,
                                                               max_pairs,
                                                               sieving,
                                                               rows);
      emitted += static_cast<std::int64_t>(pairs.size() - first);
      if (filter_pairs) {
        relative_.filter(topology_, x_t0, x_t1, 0.5 * options_.min_separation, pairs, first);
      }
      return done;
    });
    blocks_.finish();
    // The pairs apart at both ends this interval, dropped in the leaves or by the feature stage
    // (what it did not keep): the next interval builds the slot end boxes from the start when
    // they would have paid here.
    const std::int64_t kept = out.counters.candidate_pairs - candidates_before;
    slot_ends_pay_ = scratch_.apart_at_both_ends + emitted - kept >= pays;
    out.counters.candidate_pairs += sieve.settled;
    const auto t2 = Clock::now();
    out.times.refit_us += micros(t0, t1);
    out.times.traverse_us += micros(t1, t2) - blocks_.test_us();
    out.times.elementary_us += blocks_.test_us();
  }

 private:
  /// What the constructor does once the hierarchy is built.
  void reserve() {
    // Everything an interval touches is sized here; only the blocks' feature candidates and the
    // caller's findings may still grow (with the motion), and they keep their capacity — and
    // `kdop`'s relative boxes (#F × 120 bytes), sized by the first query whose trial keeps them:
    // a clip that never needs them never holds them (docs/benchmarks.md, bounded memory).
    const auto num_faces = static_cast<std::size_t>(topology_.num_triangles());
    if (!feature_stage_tests_ends(options_.min_separation))
      bounds_.vertices.reserve(static_cast<std::size_t>(topology_.num_vertices()));
    bounds_.triangles.reserve(num_faces);
    scratch_.reserve_self(bvh_);
    full_slots_.reserve(num_faces);
    if (rigid_rows_) {
      row_skip_.nodes.reserve(bvh_.nodes().size());
      row_skip_.slots.reserve(bvh_.triangle_order().size());
      rest_pairs_.reserve(rigid_rows_->rest_pairs.size());
    }
  }

  /// Certifies the rigid rows for `interval` and fills row_skip_ and rest_pairs_; the skip to
  /// walk with, or null (no rows, no bone transforms, or no row certified on any node).
  const RowSkip* certify_rows(const Interval& interval) {
    rest_pairs_.clear();
    if (!rigid_rows_ || interval.bones_t0.empty() || interval.bones_t1.empty()) return nullptr;
    certify_rigid_rows(
        *rigid_rows_, interval.bones_t0, interval.bones_t1, options_.min_separation, certified_);
    if (!row_skip<N>(bvh_, rigid_rows_->triangle_row, certified_, row_skip_)) return nullptr;
    for (const TrianglePair& p : rigid_rows_->rest_pairs) {
      if (certified_[static_cast<std::size_t>(
              rigid_rows_->triangle_row[static_cast<std::size_t>(p.a)])] != 0) {
        rest_pairs_.push_back(p);
      }
    }
    return &row_skip_;
  }

  bool relative_pairs_;
  std::shared_ptr<const RigidRows> rigid_rows_;  // null: none (`bvh` itself)
  std::vector<std::uint8_t> certified_;          // per row, this interval
  RowSkip row_skip_;
  std::vector<TrianglePair> rest_pairs_;  // the certified rows' rest pairs, this interval
  RelativePairTrial relative_;
  // Held, not copied: a serial check's baseline `bvh` lends it to the runner's method
  // (HierarchyCache::Sharing::hand_over), which refits it at its first query.
  std::shared_ptr<Bvh<N>> tree_;
  Bvh<N>& bvh_ = *tree_;
  std::shared_ptr<const SlotAdjacency> slots_ =
      shared_slot_adjacency(options_.hierarchies.get(), features_, bvh_.triangle_order());
  std::vector<std::uint8_t> full_slots_;
  // Whether the last interval had enough pairs apart at both ends for the slot end boxes to pay
  // (pairs per triangle), when ccd builds them.
  static constexpr std::int64_t kSlotEndsPayPerTriangle = 2;
  bool slot_ends_pay_ = false;
  FeatureBounds<N> bounds_;
  TraversalScratch scratch_;
  PairBlocks<N> blocks_{
      options_.block_pairs,
      block_reserve(options_.block_pairs, bvh_.leaf_size(), topology_.num_triangles())};
};

}  // namespace

template <int N>
std::unique_ptr<CullingMethod> make_bvh_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    bool relative_pairs,
    bool rigid_rows) {
  return std::make_unique<BvhMethod<N>>(name, mesh, topology, options, relative_pairs, rigid_rows);
}

template std::unique_ptr<CullingMethod> make_bvh_method<3>(
    std::string_view,
    const skinning::Mesh&,
    const skinning::Topology&,
    const MethodOptions&,
    bool,
    bool);
template std::unique_ptr<CullingMethod> make_bvh_method<8>(
    std::string_view,
    const skinning::Mesh&,
    const skinning::Topology&,
    const MethodOptions&,
    bool,
    bool);

}  // namespace skelcd::culling::detail

namespace skelcd::culling {

void prebuild_bvh_hierarchy(
    HierarchyCache& cache,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const BvhOptions& options) {
  // The key BvhMethod<3> asks the cache with (FeatureTopology::welded_triangles is a copy of the
  // topology's: the same bytes).
  cache.prebuild<3>(
      topology.welded_triangles,
      detail::welded_rest_positions(mesh, topology),
      nullptr,
      detail::traversal_only(options));
}

}  // namespace skelcd::culling
