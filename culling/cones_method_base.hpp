#pragma once
// The engine shared by the cone culling methods (`normal-cone`, `dual-cone`,
// `enhanced-dual-cone`): the culling module's AABB hierarchy over the welded triangles with a
// surface normal cone per node, refit per instant or interval; a self traversal that asks the
// method's node test before descending (into the children — the standard scheme — or into the
// four grandchildren and their six pairs — Algorithm 3's scheme); node-pair descents (Collide);
// then the shared feature and elementary stages of culling/candidates.hpp and
// culling/elementary.hpp. Internal to culling/.

#include <cstdint>
#include <memory>
#include <span>
#include <string_view>
#include <vector>

#include "culling/candidates.hpp"
#include "culling/cones.hpp"
#include "culling/cones_method.hpp"
#include "culling/contour.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/pair_blocks.hpp"

namespace skelcd::culling::detail {

class ConeMethodBase : public MethodBase, public ConeStatistics {
 public:
  void dcd(const Instant& at, FrameResult& out) override;
  void ccd(const culling::Interval& interval, FrameResult& out) override;

  [[nodiscard]] const ConeCullingStats& cone_stats() const override { return stats_; }
  [[nodiscard]] const ConeStatistics* cone_statistics() const override { return this; }
  /// Built on the first query (or here): `auto` may free a cone method before it asks one
  /// (count_dcd_pairs_at_least), and the contours are most of its set-up on cloth.
  [[nodiscard]] const NodeContours& contours() const override {
    ensure_contours();
    return contours_;
  }

  /// The hierarchy over this method's triangles, refit by each query, and the volumes of every
  /// vertex and triangle of the mesh at the last query (no edges:
  /// ccd_candidates_from_triangle_pairs forms theirs from the vertices'): `auto` traverses the
  /// pairs between its groups on these rather than on copies (docs/culling.md "Bounded memory").
  [[nodiscard]] const AabbBvh& hierarchy() const { return bvh_; }
  [[nodiscard]] const FeatureBounds<3>& feature_bounds() const { return bounds_; }
  /// Refits feature_bounds() and the wide copy of hierarchy() (Bvh::refit_wide: not its binary
  /// node volumes, nor the cones) to the static volumes of instant x: what `auto` asks before it
  /// traverses this hierarchy for a DCD itself, sieved as `bvh` does, instead of this method's
  /// cone-culled DCD (docs/dual-cone.md "`auto`'s DCD"). This method's own queries refit all.
  void refit_static(const skinning::Positions& x);
  /// The same for the interval x_t0 → x_t1: its swept volumes (grown by half the contact distance,
  /// as this method's CCD grows them), for `auto`'s CCD on this hierarchy without the cones
  /// (docs/dual-cone.md "`auto`'s CCD").
  void refit_swept(const skinning::Positions& x_t0, const skinning::Positions& x_t1);
  /// The triangle pairs this method's cone-culled DCD traversal produces at x (everything refit
  /// to x first), counted without testing them; the count stops at `cap` (the result is then cap
  /// or a leaf's pairs more). For `auto`'s choice, which only needs to know whether the count
  /// stays under a bound. Allocation-free.
  [[nodiscard]] std::int64_t count_dcd_pairs(const skinning::Positions& x, std::int64_t cap);
  /// A lower bound of count_dcd_pairs(x, cap), found without the contours: the same traversal
  /// with node_culled_without_contours, which culls every node node_culled culls (and maybe
  /// more), so it visits a subset of the nodes and produces a subset of the pairs. When it reaches
  /// `cap`, so does count_dcd_pairs, and the contours need not be built to know it.
  [[nodiscard]] std::int64_t count_dcd_pairs_at_least(
      const skinning::Positions& x, std::int64_t cap);

 protected:
  /// Where a self-test descends when its node is not culled.
  enum class Descent : std::uint8_t {
    children,       ///< SelfCollide(L), SelfCollide(R), Collide(L, R)
    grandchildren,  ///< the 4 sub-surfaces' self-tests and their 6 pairs (Algorithm 3)
  };

  /// The instant (x_t1 == x_t0, continuous false) or interval the node tests see.
  struct Interval {
    const skinning::Positions* x_t0 = nullptr;
    const skinning::Positions* x_t1 = nullptr;
    bool continuous = false;
  };

  /// @param needs_contours build the per-node contours (normal-cone, enhanced-dual-cone).
  /// @param subset when not null, the triangle ids the method covers (its hierarchy is built over
  ///        them only: pairs with a triangle outside are never reported) — for routing.
  /// @param features when not null, the mesh's feature topology built by the caller (`auto`).
  ConeMethodBase(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      Descent descent,
      bool needs_contours,
      const std::vector<std::int32_t>* subset,
      std::shared_ptr<const FeatureTopology> features = {});

  /// The surface normal test (condition 1) of node n: its cone lies in a half-space, or — when
  /// the hierarchical cone is too loose — every normal of its triangles is proven to point into
  /// the half-space of its mean normal. Sets `axis` to the proven direction.
  [[nodiscard]] bool normal_test(std::int32_t n, Eigen::Vector3d& axis);

  /// Per-interval refit beyond the normal cones (FASTCD's binormal cones). Default: nothing.
  virtual void refit_extra(const Interval& /*interval*/) {}
  /// The method's test of internal node `node`: true when its surface is proven free of
  /// self-collision over the instant / interval. Counts its failures in stats_.
  [[nodiscard]] virtual bool node_culled(std::int32_t node, const Interval& interval) = 0;
  /// True for every node that node_culled culls, without reading the contours (for
  /// count_dcd_pairs_at_least). With contours (`normal-cone`, `enhanced-dual-cone`: their test
  /// needs a node with a contour, condition 1 and then the contour's): a node with a contour
  /// whose normal test passes. Without: node_culled itself.
  [[nodiscard]] virtual bool node_culled_without_contours(
      std::int32_t node, const Interval& interval);
  /// Builds the contours when the method needs them and has not built them yet.
  void ensure_contours() const;

  AabbBvh bvh_;
  NormalConeTree cones_;
  mutable NodeContours contours_;  ///< read after ensure_contours()
  ContourTester contour_tester_;
  ConeCullingStats stats_;

 private:
  /// Refits everything a cone-culled DCD at x reads (static volumes, the hierarchy with its binary
  /// node volumes, the cones); returns the instant as the node tests see it.
  Interval refit_instant(const skinning::Positions& x);
  /// count_dcd_pairs and count_dcd_pairs_at_least (x checked): the DCD traversal at x, its pairs
  /// counted up to `cap`, culled by node_culled or by node_culled_without_contours.
  std::int64_t count_pairs(const skinning::Positions& x, std::int64_t cap, bool without_contours);
  void traverse(const Interval& interval, std::int64_t& bv_tests);
  /// Collide(a, b) of Algorithm 3: every triangle pair (one under a, one under b) whose volumes
  /// overlap, as (min, max); the node with more triangles is split first.
  void collide(std::int32_t a, std::int32_t b, std::int64_t& bv_tests);
  /// The triangle pairs inside one leaf (leaf_size > 1).
  void leaf_self(std::int32_t leaf, std::int64_t& bv_tests);

  /// Tests the pairs gathered so far (a block) once block_pairs are waiting: DCD and CCD alike.
  /// While counting (count_dcd_pairs), counts and drops them instead.
  void pair_added() {
    if (counting_) {
      counted_ += static_cast<std::int64_t>(blocks_.pairs().size());
      blocks_.pairs().clear();
      return;
    }
    blocks_.flush_if_full();
  }
  /// count_dcd_pairs has counted up to its cap: the traversal stops.
  [[nodiscard]] bool counted_enough() const { return counting_ && counted_ >= count_cap_; }

  Descent descent_;
  bool cull_enabled_;
  bool needs_contours_;
  mutable bool contours_built_ = false;
  bool without_contours_ = false;  ///< count_dcd_pairs_at_least is counting
  FeatureBounds<3> bounds_;
  std::vector<std::int32_t> self_stack_;
  std::vector<std::pair<std::int32_t, std::int32_t>> pair_stack_;
  PairBlocks<3> blocks_;
  bool counting_ = false;  ///< count_dcd_pairs is running
  std::int64_t counted_ = 0;
  std::int64_t count_cap_ = 0;
};

}  // namespace skelcd::culling::detail
