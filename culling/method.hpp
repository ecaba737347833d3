#pragma once
// The culling method interface (a run-time choice, DESIGN.md "Methods"): a method is built once for
// a mesh's topology and then answers, per instant (DCD) or per interval (CCD), which primitive pairs
// collide — through the shared elementary tests of ccd/ at the requested accuracy.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "culling/bvh.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
#include "culling/frame_result.hpp"
#include "culling/rigid_rows.hpp"
#include "skinning/mesh.hpp"
#include "skinning/pose.hpp"
#include "skinning/topology.hpp"

namespace skelcd::segmentation {
struct Segmentation;
}

namespace skelcd::culling {

class HierarchyCache;  // culling/hierarchy_cache.hpp

/// Parameters of methods declared above culling/ (radial view, paper 002 §5).
struct MethodParameters {
  double gamma = 0.05;     ///< `dynamic`'s merge threshold γ, in [0, 1]
  std::uint64_t seed = 1;  ///< `dynamic`'s seed-cluster draws
};

struct MethodOptions {
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  /// Contact distance (coordinate units); 0 = touching counts. CCD bounds are inflated by half of
  /// it each, so features within this distance always reach the elementary test.
  double min_separation = 0.0;
  /// Hierarchy build options of the hierarchy methods (`bvh`, `kdop`).
  BvhOptions bvh{};
  /// The elementary tests to call; null members mean the ccd/ kernels.
  ElementaryTests elementary{};
  /// The mesh's segmentation (atomic clusters and observers), for methods that need one
  /// (MethodNeeds::segmentation); null when the run asks for DCD only or the model has no rig.
  std::shared_ptr<const segmentation::Segmentation> segmentation{};
  /// Bones of the rig whose transforms every query will carry (Interval::bones_t0/t1); 0 when the
  /// motion has no skeleton. Methods that need bone poses are built, and chosen by `auto`, only
  /// when it is > 0.
  std::int32_t num_bones = 0;
  MethodParameters parameters{};
  /// The mesh's rigid rows (culling/rigid_rows.hpp), for methods that take them
  /// (MethodInfo::takes_rigid_rows): their CCD skips the pairs of two triangles of one row the
  /// interval certifies, from the bone transforms it carries, and tests the row's rest pairs
  /// instead. Null, or an interval without bone transforms: no pair is skipped.
  std::shared_ptr<const RigidRows> rigid_rows{};
  /// Triangle pairs per block of the feature and elementary stages (docs/culling.md "Bounded
  /// memory"): what a query holds at once grows with it, not with the motion. The findings do not
  /// depend on it; tests make it small to cut a query into many blocks. ≥ 1.
  std::size_t block_pairs = kCcdBlockPairs;
  /// The mesh's FeatureTopology, when the caller built one to share (the runner: one for all its
  /// methods, their DCD updaters and its threads; docs/culling.md "Bounded memory"). A method
  /// takes it only when it was built from the very mesh and topology objects it is given
  /// (FeatureTopology::built_from); otherwise, and when null, it builds its own.
  std::shared_ptr<const FeatureTopology> features{};
  /// Hierarchies shared with the methods built beside this one (HierarchyCache: the first to ask
  /// builds, the others copy). Null: each method builds its own. The runner gives one to the
  /// methods of a parallel run's workers and closes it once they are built.
  std::shared_ptr<HierarchyCache> hierarchies{};
  /// Whether the run asks this method for DCD queries (false: CCD only). A method may build what
  /// only its DCD needs while `hierarchies` is open when true (`dynamic`'s DCD tree, a copy of the
  /// baseline's), and never when false.
  bool dcd_queries = true;
};

/// Where one connected component (Topology::components) goes under `auto` (routed_method.hpp).
struct ComponentRoute {
  std::int32_t component = -1;  ///< index into Topology::components
  std::int32_t part = -1;       ///< Mesh part of its first triangle
  bool closed = false;          ///< no boundary and no non-manifold edge
  /// Open, but every hole a small loop the closed group's method closes itself
  /// (MethodInfo::closes_holes_up_to): routed with the closed components.
  bool capped = false;
  /// Open, not capped, and smaller than RoutingOptions::min_open_triangles: routed with the
  /// closed components (whose method tests it as it tests any open part: like `bvh` for the
  /// radial-view methods).
  bool small = false;
  std::int32_t num_triangles = 0;
  std::string method;  ///< the method testing its pairs within its group
};

class ConeStatistics;  // culling/cones_method.hpp

/// One instant as a method sees it (a DCD query).
struct Instant {
  /// #W × 3 welded positions (finite: the runner checks).
  const skinning::Positions& x;
  /// The motion's bone transforms at this instant (skinning::Motion::bone_transforms); empty when
  /// it has no skeleton.
  std::span<const skinning::BoneTransform> bones{};
  std::int32_t sample = -1;  ///< the motion's sample, -1 when not one
};

/// One interval as a method sees it (a CCD query): linear motion from x_t0 to x_t1.
struct Interval {
  const skinning::Positions& x_t0;  ///< #W × 3 welded positions at the start
  const skinning::Positions& x_t1;  ///< … and at the end
  /// Bone transforms at the two ends (what moves radial view's observers); empty when the motion
  /// has no skeleton.
  std::span<const skinning::BoneTransform> bones_t0{};
  std::span<const skinning::BoneTransform> bones_t1{};
  std::int32_t sample_t0 = -1;  ///< the motion's samples at the ends, -1 when not samples
  std::int32_t sample_t1 = -1;
};

class CullingMethod {
 public:
  virtual ~CullingMethod() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;

  /// What some methods report beside their findings, asked of any method (no casts): which
  /// method each component used (`auto`; empty for the others, see routes_of) and the cone
  /// methods' culling statistics of the last query (null for the others).
  [[nodiscard]] virtual std::span<const ComponentRoute> component_routes() const { return {}; }
  [[nodiscard]] virtual const ConeStatistics* cone_statistics() const { return nullptr; }
  /// The FeatureTopology the method works on, when it has one to share, in whatever owner order
  /// it chose (`dynamic`: rims first): what a user that reads no ownership (the runner's DCD
  /// updaters) may take instead of holding another. Null: none to share.
  [[nodiscard]] virtual std::shared_ptr<const FeatureTopology> shared_features() const {
    return {};
  }
  /// Whether the last CCD's row (findings and counters) is the one this method gives for that
  /// interval whenever the query before it ended at the interval's start: what a later query of
  /// the same held interval would give, which the runner may then hand on instead (docs/check.md,
  /// "Static intervals"). True for a method that keeps nothing between queries; a radial-view
  /// method's is false after an interval whose start it had to find by a DCD of its own.
  [[nodiscard]] virtual bool last_ccd_row_reusable() const { return true; }

  /// Intersecting triangle pairs at one instant: every pair of distinct triangles with a common
  /// point beyond the vertices or edge they share (exact), except part-excluded pairs and
  /// duplicate faces on the same three vertices.
  /// @param out cleared by the caller; filled with dcd_pairs, counters and times.
  /// @throws InvalidInput when at.x does not have #W rows.
  /// @note Allocation-free after the first calls, except when `out` or the method's candidate
  ///       buffers must grow beyond what an earlier call needed.
  void detect_dcd(const Instant& at, FrameResult& out) { dcd(at, out); }
  void detect_dcd(const skinning::Positions& x, FrameResult& out) { dcd(Instant{.x = x}, out); }

  /// VF and EE contacts over the interval: every vertex-face and edge-edge pair not sharing a
  /// vertex (and not part-excluded) that the elementary test reports, each tested once.
  /// @param out cleared by the caller; filled with contacts, counters and times.
  /// @throws InvalidInput when x_t0 or x_t1 does not have #W rows, or the method needs bone
  ///         transforms (MethodInfo::needs) and the interval carries none.
  void detect_ccd(const Interval& interval, FrameResult& out) { ccd(interval, out); }
  void detect_ccd(
      const skinning::Positions& x_t0, const skinning::Positions& x_t1, FrameResult& out) {
    ccd(Interval{.x_t0 = x_t0, .x_t1 = x_t1}, out);
  }

 protected:
  /// What a method implements (the detect_* calls above forward here).
  virtual void dcd(const Instant& at, FrameResult& out) = 0;
  virtual void ccd(const Interval& interval, FrameResult& out) = 0;
};

/// Names of the registered methods (culling/method_registry.hpp), in listing order.
[[nodiscard]] std::vector<std::string> method_names();

/// Builds the registered method `name` for `mesh` / `topology` (the method copies what it
/// needs). culling/'s own: `brute` (every feature pair, volume-filtered: the reference on small
/// meshes), `bvh` (AABB hierarchy), `kdop` (16-DOP hierarchy), the cone methods and `auto`. All
/// that may not miss report identical contacts with the `exact` accuracy; docs/culling.md says
/// what may differ with `conservative` (false positives only).
/// @throws InvalidInput for an unknown name (the message lists every registered method), a mesh
///         and topology that disagree, a negative or non-finite min_separation, or
///         min_separation > 0 with the `exact` accuracy.
[[nodiscard]] std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {});

/// The options checks every method makes when it is built (make_method's), for a method that
/// builds a part later (clustering::RadialViewMethod's DCD tree) and must refuse bad options at
/// once.
/// @throws InvalidInput for a negative or non-finite min_separation, min_separation > 0 with the
///         `exact` accuracy, or block_pairs = 0.
void check_method_options(const MethodOptions& options);

}  // namespace skelcd::culling
