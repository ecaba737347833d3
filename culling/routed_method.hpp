#pragma once
// `auto`: each connected component of a mesh goes to the culling method that fits it (DESIGN.md
// "Routing"). Components with an open boundary go to `enhanced-dual-cone` (radial-view culling
// needs a closed surface); closed components go to the registered closed-part method with the
// highest priority whose needs are met (culling/method_registry.hpp: `dynamic` on a rig's clip),
// else to kClosedFallbackMethod (`bvh`). Pairs of triangles in different groups go through a BVH
// pair traversal between the groups' hierarchies. Everything ends in the shared feature and
// elementary stages over the whole mesh, so contacts are reported in the mesh's own welded
// numbering, canonical and sorted, as by any other method. To force one method for a whole object,
// call make_method with its name instead of "auto".

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling {

/// What closed components use when no registered closed-part method's needs are met.
inline constexpr std::string_view kClosedFallbackMethod = "bvh";

struct RoutingOptions {
  /// Method for components with an open boundary: `enhanced-dual-cone` (default),
  /// `normal-cone`, `dual-cone` or `bvh`.
  std::string open_method = "enhanced-dual-cone";
  /// Method for closed components: empty picks the best registered closed-part method whose needs
  /// are met, else kClosedFallbackMethod. Otherwise any name above, or any registered method.
  std::string closed_method;
  /// With `closed_method` empty: a mesh of fewer than all_closed_below_triangles triangles whose
  /// every component is closed, has fewer than min_open_triangles triangles, or is open only at
  /// holes the registered closed-part method of highest priority caps (whether its needs are met
  /// or not; none for the open method) goes whole to this method instead. `bvh` by default: on
  /// the real characters that are closed throughout, `dynamic` took 0.81-1.48x `bvh`'s time per
  /// interval, 1.09x in geometric mean, since every method's feature stage drops what radial
  /// view culls there, and 1.16x on BCN_Epileptic, capped throughout (docs/benchmarks.md "auto
  /// against bvh: the default method", docs/dual-cone.md "Routing"). Empty: the closed method, as
  /// for any mesh. It must need nothing beyond the mesh (no bones, no segmentation).
  std::string all_closed_method = std::string(kClosedFallbackMethod);
  /// The size from which a mesh closed throughout goes to the closed method after all (`dynamic`
  /// on a rig's clip, else `bvh` as well): on the denser copies of real characters of 24,576 to
  /// 112,128 triangles a default check (both queries, two threads) took 1.08-1.55x less time
  /// with `dynamic` than with `bvh`, its segmentation and local hierarchies included (within the
  /// noise at 28,032), and 0.90-1.02x on those of 6,144 and 13,824 (docs/benchmarks.md "`auto` on
  /// dense characters").
  /// 0: whatever the size.
  std::int64_t all_closed_below_triangles = 20000;
  /// Open components with fewer triangles go with the closed ones (ComponentRoute::small): the
  /// cone methods have nothing to gain on a small open part, and a group of its own costs `auto`
  /// the group's hierarchies and the traversal between the groups (docs/dual-cone.md, "Routing").
  std::int32_t min_open_triangles = 256;
  /// A cone group's DCD takes either its method's cone-culled traversal or the sieved traversal
  /// of `bvh` on the group's hierarchy — the same pairs either way (docs/dual-cone.md "`auto`'s
  /// DCD"). Chosen once, at rest: the cones when their traversal produces fewer than
  /// 1/dcd_cone_share of the pairs whose volumes overlap; 0: never the cones.
  std::int64_t dcd_cone_share = 8;
  /// The same choice for CCD (docs/dual-cone.md "`auto`'s CCD"), whose pairs each cost more (the
  /// feature stage, the conservative kernels), so that the cones pay at a smaller cull: the
  /// cones' traversal, or the plain one of `bvh` on the group's hierarchy.
  std::int64_t ccd_cone_share = 2;
};

/// The methods `auto` uses for the open and the closed components under `options`: {open, closed}.
/// The closed one, unless `routing` names one, is the registered method of RouteKind::closed with
/// the highest priority whose needs the options meet (`dynamic` with a segmentation and bone
/// poses), else kClosedFallbackMethod. (RoutingOptions::all_closed_method, which may take a mesh
/// closed throughout instead, needs nothing beyond the mesh.)
[[nodiscard]] std::vector<std::string> auto_group_methods(
    const MethodOptions& options, const RoutingOptions& routing = {});

/// Whether `auto` sends the whole mesh to RoutingOptions::all_closed_method (every component
/// closed, under min_open_triangles or capped, fewer triangles than all_closed_below_triangles,
/// `closed_method` not named), so that what only the closed method needs (a segmentation) need
/// not be made: the answer depends on the topology alone.
[[nodiscard]] bool routes_whole_mesh_to_all_closed_method(
    const skinning::Topology& topology, const RoutingOptions& routing = {});

/// What `auto` gives each of its groups, decided from the topology alone (before any method or
/// segmentation exists: a check's set-up, a scene's plan).
struct AutoGroups {
  bool whole = false;                  ///< routes_whole_mesh_to_all_closed_method
  std::int32_t open_components = 0;    ///< for the open method (cones): open, large, not capped
  std::int32_t closed_components = 0;  ///< for the closed method: closed, small or capped
};

/// The groups of route_components on a mesh whose closed method is, with `rig`, the registered
/// closed-part method of highest priority (`dynamic`, which a rig's clip gets once segmented: its
/// hole capping decides which open components join the closed ones), and kClosedFallbackMethod
/// otherwise. A rig's clip needs a segmentation under `auto` only when the closed group is not
/// empty and the whole mesh does not go to all_closed_method; it runs cones only when the open
/// group is not empty.
[[nodiscard]] AutoGroups auto_groups(
    const skinning::Topology& topology, bool rig, const RoutingOptions& routing = {});

/// The plan of make_routed_method: one route per component, in component order. Uses
/// Topology::components, or finds the edge-connected components itself when that is empty.
/// @throws InvalidInput naming the method when a group's method is unknown or unusable here.
[[nodiscard]] std::vector<ComponentRoute> route_components(
    const skinning::Topology& topology,
    const MethodOptions& options = {},
    const RoutingOptions& routing = {});

/// Builds the `auto` method (what make_method("auto", …) returns, with default RoutingOptions).
/// @throws InvalidInput as make_method and route_components.
[[nodiscard]] std::unique_ptr<CullingMethod> make_routed_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options = {},
    const RoutingOptions& routing = {});

/// What `auto` holds for its own traversal (its groups' self pairs under `bvh`, the pairs between
/// the groups) beside its group methods (docs/culling.md "Bounded memory").
struct RoutedStructures {
  /// Hierarchies `auto` built itself: a group traversed here that has no cone method (`bvh`).
  std::int32_t own_hierarchies = 0;
  /// Group hierarchies read from the group's cone method rather than copied.
  std::int32_t shared_hierarchies = 0;
  /// Feature volumes refit by `auto` itself (false: a cone group method's are read, or nothing is
  /// traversed here).
  bool own_feature_bounds = false;
  /// Distinct feature topologies (culling::FeatureTopology) held by `auto` and those of its group
  /// methods that are culling/'s own: 1 when its cone group methods share `auto`'s. (A whole-mesh
  /// closed method, `dynamic`, gets another mesh and counts apart when it is one of culling/'s.)
  std::int32_t feature_topologies = 0;
};

/// The structures of an `auto` method (make_routed_method).
/// @throws InvalidInput when `method` is not one.
[[nodiscard]] RoutedStructures routed_structures(const CullingMethod& method);

/// The routes of `method` (CullingMethod::component_routes): which method each component used
/// under `auto` (for the log), empty for the other methods.
[[nodiscard]] std::span<const ComponentRoute> routes_of(const CullingMethod& method);

}  // namespace skelcd::culling
