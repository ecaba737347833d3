#pragma once
// `rvbc` and `dynamic`: radial-view culling at run time (paper 002, §3, §5, §6), behind the
// culling::CullingMethod interface. Per interval: classify every triangle against its (mega)
// cluster's observer, skip the pairs of one mega cluster whose features are all positive (or all
// negative), traverse the rest through the atomic clusters' local hierarchies and the global one,
// filter with relative AABBs, then the shared feature stage and elementary tests of culling/, one
// bounded block of pairs at a time (culling/pair_blocks.hpp).
//
// The radial-view argument has preconditions; this method checks them instead of assuming them
// (docs/radial-view.md, "The local guard"): the argument is applied only to closed, consistently
// oriented components; where such a component intersects itself at the interval's start, only
// triangles of its uncut patches with the component's front winding number may be skipped (one
// exact ray per patch); and wherever a contact touches a skippable triangle, that triangle's
// skipped pairs are tested too, round after round until no new contact touches one (the
// argument guarantees only the first contact). Contacts therefore equal those of `bvh` exactly. DCD
// queries are answered by the `bvh` method: orientation at one instant says nothing about
// interpenetration.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "clustering/bone_poses.hpp"
#include "clustering/cluster_set.hpp"
#include "clustering/ghost_caps.hpp"
#include "clustering/mega_clusters.hpp"
#include "clustering/side_winding.hpp"
#include "culling/candidates.hpp"
#include "culling/cluster_checks.hpp"
#include "culling/elementary.hpp"
#include "culling/feature_topology.hpp"
#include "culling/incremental_dcd.hpp"
#include "culling/method.hpp"
#include "culling/pair_blocks.hpp"
#include "culling/relative_aabb.hpp"
#include "culling/traversal.hpp"
#include "segmentation/segmentation.hpp"

namespace skelcd::clustering {

struct RadialViewOptions {
  /// Mega clusters (`dynamic`) or fixed atomic clusters (`rvbc`), γ, seed.
  MegaClusterOptions clusters{};
  /// Relative AABB filter on non-adjacent candidate pairs (§6).
  bool relative_aabb = true;
  /// Check the preconditions (the local guard: patches at the start, re-tests around every
  /// self-contact). Off only to show what the bare theory misses (tests/clustering): then
  /// contacts may be lost.
  bool guard = true;
  /// Give the features on the rims between atomic clusters and between rest classes to one side
  /// of each rim (culling::FeatureTopology's owner order), so that fewer triangles own an impure
  /// feature and are tested as Hᵘ. Off: triangle order (tests compare the two).
  bool rims_first = true;
};

/// What the last detect_ccd did beyond the counters of FrameResult.
struct RadialViewStats {
  std::int32_t components = 0;         ///< components of the mesh
  std::int32_t components_culled = 0;  ///< components where pairs may be skipped
  std::int32_t components_open = 0;    ///< not closed / not consistently oriented / mixed parts
  /// Components whose start was known from a full DCD made here (no DCD at these positions, no
  /// previous interval ending there).
  std::int32_t components_dcd = 0;
  std::int64_t dcd_pass_pairs = 0;    ///< candidate triangle pairs of that DCD
  std::int32_t components_dirty = 0;  ///< self-intersecting at the start (patches classified)
  /// Components with a triangle escalated: a self-contact touched its skippable triangles.
  std::int32_t components_escalated = 0;
  std::int64_t relative_aabb_culled = 0;  ///< candidate pairs removed by the relative AABB filter
  /// Overlapping skipped pairs tested on escalation (a certified rigid row's own not counted).
  std::int64_t skipped_pairs_retested = 0;
  std::int64_t escalation_contacts = 0;  ///< contacts found only by the escalation passes
  /// Blocks of candidate triangle pairs tested, all passes (MethodOptions::block_pairs each).
  std::int64_t blocks = 0;
  // The local guard (docs/radial-view.md, "The local guard").
  std::int64_t triangles_cut = 0;  ///< in a self-intersecting pair of their component
  std::int64_t patches = 0;        ///< uncut patches of the dirty components
  /// … whose front winding number is known: a ray decided it, or the patch is the only one of
  /// its component large enough to classify (its value is the component's, no ray needed)
  std::int64_t patches_classified = 0;
  std::int64_t rays = 0;                 ///< rays cast to classify patches
  std::int64_t triangles_kept_out = 0;   ///< of dirty components, not skippable (cut, off-value)
  std::int64_t triangles_escalated = 0;  ///< skippable triangles whose skipped pairs were tested
  std::int32_t escalation_rounds = 0;    ///< rounds until no new contact touched one
  std::int32_t ghost_loops = 0;          ///< boundary loops closed by ghost triangles
  std::int64_t ghost_contacts = 0;       ///< contacts of a ghost's features (used, not reported)
  std::int64_t ghost_pairs_skipped = 0;  ///< candidate pairs of two ghosts, never tested
  // Rigid rows (culling/rigid_rows.hpp, docs/radial-view.md "Rigid rows").
  std::int32_t rows_certified = 0;       ///< rows the interval certifies
  std::int64_t rigid_pairs_skipped = 0;  ///< walked pairs of two triangles of one such row
  /// Cluster walks not made (a cluster against itself, or two clusters) because every triangle
  /// in them has the same certified row.
  std::int64_t rigid_walks_skipped = 0;
  std::int64_t rest_pairs = 0;  ///< those rows' rest pairs, tested instead
};

class RadialViewMethod final : public culling::CullingMethod {
 public:
  /// @param name "rvbc" or "dynamic" (the name reported; `options.clusters.merge` decides).
  /// @param segmentation of `mesh` (same triangle order).
  /// @param poses for drivers that select bone poses themselves before each query (tests); may
  ///   be null, and is used only for an interval that carries no bone transforms of its own.
  /// @param num_bones bones of the rig (transform count the observers need).
  /// @throws InvalidInput as culling::make_method for bad method options, and when the
  ///   segmentation does not fit the mesh.
  RadialViewMethod(
      std::string name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      std::shared_ptr<const segmentation::Segmentation> segmentation,
      std::shared_ptr<const BonePoses> poses,
      std::int32_t num_bones,
      const culling::MethodOptions& method_options,
      const RadialViewOptions& options);

  [[nodiscard]] std::string_view name() const override { return name_; }
  /// Its features in rim-first owner order (of the capped mesh when it has ghost caps).
  [[nodiscard]] std::shared_ptr<const culling::FeatureTopology> shared_features() const override {
    return features_;
  }
  /// False after an interval whose start pairs took a DCD of this method's own (its counters
  /// hold that DCD's; a query with the previous interval's end state would not).
  [[nodiscard]] bool last_ccd_row_reusable() const override { return !start_by_own_dcd_; }

  /// The `bvh` method's DCD (recorded: a following detect_ccd from the same positions knows which
  /// components are free of self-intersection without a pass of its own).
  void dcd(const culling::Instant& at, culling::FrameResult& out) override;

  /// @throws InvalidInput for positions with the wrong row count, or when the interval carries no
  ///   bone transforms and no BonePoses were selected.
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override;

  [[nodiscard]] const ClusterSet& clusters() const { return clusters_; }
  /// The classes and mega clusters of the last detect_ccd.
  [[nodiscard]] const IntervalClasses& last_classes() const { return classes_; }
  [[nodiscard]] const RadialViewStats& last_stats() const { return stats_; }
  [[nodiscard]] const RadialViewOptions& options() const { return options_; }
  /// The intersecting pairs at the last interval's start (of the capped mesh when it has ghost
  /// caps), however they were found: recorded, carried or from start_dcd; for tests.
  [[nodiscard]] const std::vector<culling::TrianglePair>& start_pairs() const {
    return start_pairs_;
  }
  /// Whether it holds a whole-mesh DCD hierarchy (built at the first detect_dcd; see dcd_); for
  /// tests.
  [[nodiscard]] bool holds_dcd() const { return dcd_ != nullptr; }

 private:
  enum class Status : std::uint8_t { unknown, clean, dirty };

  /// The mesh the method works on: `mesh` with its small holes capped (ghost_caps.hpp), or `mesh`.
  RadialViewMethod(
      std::string name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      std::unique_ptr<GhostCaps> ghosts,
      std::shared_ptr<const segmentation::Segmentation> segmentation,
      std::shared_ptr<const BonePoses> poses,
      std::int32_t num_bones,
      const culling::MethodOptions& method_options,
      const RadialViewOptions& options);
  /// `x` (the real mesh's welded positions), or it with the ghost centres placed, in `capped`.
  const skinning::Positions& with_ghosts(
      const skinning::Positions& x, skinning::Positions& capped) const;
  /// Drops the findings of ghost features from `out` and renumbers edges to the real mesh's.
  void drop_ghosts(culling::FrameResult& out);
  /// The relative AABB filter runs on the cluster pairs: when asked for and the shared feature
  /// stage does not make its test itself (with a contact distance: culling/candidates.hpp).
  [[nodiscard]] bool filters_pairs() const {
    return options_.relative_aabb &&
           !culling::feature_stage_tests_ends(method_options_.min_separation);
  }

  void check_positions(const skinning::Positions& x, const char* call, const char* which) const;
  /// The intersecting pairs at x_t0 (known, carried or from a DCD here), each component's status
  /// and the cut triangles.
  void start_status(const skinning::Positions& x_t0, culling::FrameResult& out);
  /// The uncut patches of the dirty culled components and their front winding numbers: which
  /// triangles may be skipped (skippable_). Needs the hierarchies refit over the interval's swept
  /// volumes (they contain the triangles at x_t0): the rays gather their triangles through them.
  void classify_patches(const skinning::Positions& x_t0);
  /// The patch partition of the dirty culled components (patch_, patch_order_, patch_offsets_,
  /// component_patches_) from cut_, status_ and culled_.
  void build_patches();
  /// The triangles of component k whose swept boxes either segment of `ray` may meet, into
  /// ray_candidates_: every triangle of k that can meet them (count_winding's precondition).
  void gather_ray_candidates(std::int32_t k, const WindingRay& ray);
  /// gather_ray_candidates' for atomic cluster a: its triangles whose boxes may_meet the ray.
  template <class MayMeet>
  void gather_ray_cluster(std::int32_t a, const MayMeet& may_meet);
  void compute_masks();
  /// Streams the pairs the masks do not skip into blocks_ (a query started there), each
  /// installment through the relative AABB filter; returns the pairs found before the filter.
  std::int64_t traverse(double half_width, culling::FrameResult& out);
  /// Marks the skippable triangles at the vertices of out.contacts that are not marked yet
  /// (round `round`), appending them to frontier_.
  void escalate(const culling::FrameResult& out, std::int32_t round);
  /// Streams the skipped pairs of frontier_'s triangles into blocks_ (each once: not with a
  /// triangle of an earlier round), through the relative AABB filter; returns the pairs found.
  std::int64_t retest_frontier(std::int32_t round, double half_width, culling::FrameResult& out);
  /// Certifies the rigid rows for `interval` (its own bone transforms; none without them):
  /// row_of_ gets each triangle's row when certified, else −1, and rest_pairs_ the certified
  /// rows' rest pairs; rows_live_ says whether any row is certified.
  void certify_rows(const culling::Interval& interval);
  /// Removes from pairs[first, end) every pair of two triangles of one certified row (their
  /// order kept) and returns how many: no such pair can touch (culling/rigid_rows.hpp).
  std::int64_t drop_row_pairs(std::vector<culling::TrianglePair>& pairs, std::size_t first) const;
  /// Streams rest_pairs_ into blocks_ (a query started there), through the relative AABB filter.
  void stream_rest_pairs(double half_width);
  void record_dcd(const skinning::Positions& x, const culling::FrameResult& result);
  /// detect_dcd's hierarchy (dcd_): `bvh`'s tree over the welded triangles and the slots its fan
  /// sieve reads (culling/sieved_dcd.hpp).
  struct DcdTree {
    /// Through `cache` when not null: the tree a copy of the baseline's `bvh` (or another
    /// worker's), the slots shared with the other workers.
    DcdTree(
        culling::HierarchyCache* cache,
        const std::shared_ptr<const culling::FeatureTopology>& features,
        const skinning::Positions& rest,
        const culling::BvhOptions& options);
    std::shared_ptr<culling::AabbBvh> tree;  // lent by the cache (a serial check's baseline)
    culling::AabbBvh& bvh = *tree;
    std::shared_ptr<const culling::SlotAdjacency> slots;
    std::vector<std::uint8_t> full_slots;  // the sieve's per slot, at each detect_dcd
  };
  /// dcd_, built when there is none (through `cache` when not null).
  DcdTree& dcd_tree(culling::HierarchyCache* cache = nullptr);
  /// The DCD at an interval's start that no DCD or previous interval left the pairs of: through
  /// the method's own hierarchies (the atomic clusters' and the global one, refit over the static
  /// volumes at x) and blocks_, into out (dcd_pairs sorted, counters, times) — no whole-mesh
  /// hierarchy built or held for it.
  void start_dcd(const skinning::Positions& x, culling::FrameResult& out);

  std::string name_;
  // Ghost caps (built before everything below, which works on the capped mesh); the capped
  // mesh and topology are released once the members are built.
  std::unique_ptr<GhostCaps> ghosts_;
  bool ghosts_own_real_features_ = false;  // never, by construction (checked when built)
  std::int32_t real_vertices_ = 0;
  std::int32_t real_triangles_ = 0;
  skinning::Positions capped_x0_, capped_x1_;
  std::shared_ptr<const segmentation::Segmentation> segmentation_;
  std::shared_ptr<const BonePoses> poses_;
  std::int32_t num_bones_ = 0;
  // The features in rim-first owner order, shared with the DCD updater and the DCD hierarchy
  // (neither reads ownership).
  std::shared_ptr<const culling::FeatureTopology> features_;
  const culling::FeatureTopology& topology_;  // *features_
  ClusterSet clusters_;
  culling::MethodOptions method_options_;
  RadialViewOptions options_;
  culling::ElementaryTests tests_;
  ccd::CcdOptions ccd_options_;
  // The intersecting pairs from one end to the next; its incidences (vertex → triangles, edge →
  // triangles) serve the patches and masks too.
  culling::DcdUpdater updater_;
  // detect_dcd's hierarchy: `bvh`'s (its tree and the slots its fan sieve reads) over the used
  // mesh's welded rest positions (dcd_rest_, freed once it is built), built at the first
  // detect_dcd, which traverses it into the method's own volumes (bounds_) and blocks (blocks_).
  // A CCD-only check never builds it: an interval's start DCD goes through the method's own
  // hierarchies (start_dcd; docs/radial-view.md, "Memory").
  skinning::Positions dcd_rest_;
  std::unique_ptr<DcdTree> dcd_;
  MegaClusterBuilder builder_;
  std::vector<std::int32_t> face_neighbours_;  // 3 per triangle (built with them): build_patches'
  static constexpr std::int32_t kNoNeighbour = -1;
  static constexpr std::int32_t kNeighboursListed = -2;
  std::vector<std::int32_t> component_offsets_, component_triangles_;  // CSR component → triangles

  // Per interval.
  IntervalObservers observers_;
  IntervalClasses classes_;
  RadialViewStats stats_;
  culling::FeatureBounds<3> bounds_;
  culling::RelativeAabbFilter relative_filter_;
  std::vector<culling::Aabb> cluster_bounds_;
  std::vector<std::uint8_t> triangle_mask_;
  std::vector<culling::ClassMasks> node_masks_;  // per atomic cluster
  std::vector<std::int32_t> triangle_label_;     // compute_masks'
  std::vector<Status> status_;                   // per component, at the interval's start
  std::vector<std::uint8_t> culled_;     // per component: pairs may be skipped this interval
  std::vector<std::uint8_t> cut_;        // per triangle: in a self-intersecting pair at the start
  std::vector<std::uint8_t> skippable_;  // per triangle: its patch has its component's value
  std::vector<std::uint8_t> taken_;      // build_patches': cut, or in a patch already
  std::vector<std::int32_t> patch_order_, patch_offsets_;  // CSR patch → triangles (BFS order)
  std::vector<std::pair<std::int32_t, std::int32_t>> patch_sizes_;  // (−size, patch) to classify
  std::vector<std::int32_t> component_patches_;  // CSR component → its patches (ids)
  std::vector<std::int32_t> escalated_;  // per triangle: the round it was escalated in, or 0
  std::vector<std::int32_t> frontier_;   // triangles escalated in the current round
  std::vector<std::uint8_t> component_escalated_;
  std::vector<culling::TrianglePair> cluster_pairs_;
  // Rigid rows (MethodOptions::rigid_rows, when given for this mesh's triangles): per row this
  // interval, per triangle its certified row or −1, and the certified rows' rest pairs.
  std::shared_ptr<const culling::RigidRows> rigid_rows_;
  std::vector<std::uint8_t> row_certified_;
  std::vector<std::int32_t> row_of_;
  std::vector<culling::TrianglePair> rest_pairs_;
  // Per atomic cluster: the row all its triangles share, or −1 (built with the rows); this
  // interval, that row when certified, else −1 (its walks then hold only pairs to drop).
  std::vector<std::int32_t> cluster_row_, cluster_live_row_;
  bool rows_live_ = false;
  // The candidate triangle pairs of a pass, in bounded blocks (docs/culling.md "Bounded memory").
  culling::PairBlocks<3> blocks_;
  culling::TraversalScratch scratch_;
  std::vector<std::int32_t> node_stack_;
  std::vector<std::int32_t> ray_stack_, ray_local_stack_,
      ray_candidates_;  // gather_ray_candidates'

  // The intersecting pairs at the interval's start, and what may tell them without a DCD: the
  // last detect_dcd (at dcd_x_) and the pairs at the last interval's end (carry_x_), updated from
  // its contacts (culling/incremental_dcd.hpp).
  std::vector<culling::TrianglePair> start_pairs_;
  bool has_carry_ = false;
  skinning::Positions carry_x_;
  std::vector<culling::TrianglePair> carry_pairs_;
  bool has_dcd_ = false;
  /// The last interval's start pairs came from a DCD made for it (neither of the two above).
  bool start_by_own_dcd_ = false;
  skinning::Positions dcd_x_;
  std::vector<culling::TrianglePair> dcd_pairs_;
  culling::FrameResult scratch_result_;
};

}  // namespace skelcd::clustering
