#pragma once
// The methods a check can run, each declared once where it is implemented: its name, one line
// for --help, what it needs beyond the mesh, whether blocks of samples may run on several
// workers, whether it may miss contacts by design, where `auto` may send components to it, and
// its factory. culling/ declares its own methods; modules above declare theirs (clustering:
// `rvbc`, `dynamic`) with a static registration in their own files. make_method, the runner's
// plan, `auto`'s routing, --help, `bench` and scenes all read this one list
// (docs/architecture.md, "Adding a method").

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "culling/method.hpp"

namespace skelcd::culling {

/// What a method needs beyond the mesh and its topology.
struct MethodNeeds {
  /// Bone transforms at both ends of every interval (Interval::bones_t0/t1): a rig's clip.
  bool bone_poses = false;
  /// MethodOptions::segmentation. Given none (a run that asks for DCD only), the method must
  /// still answer DCD queries.
  bool segmentation = false;
};

/// Which components `auto` may send to a method.
enum class RouteKind : std::uint8_t {
  none,    ///< never chosen by `auto`
  closed,  ///< closed components (no boundary, no non-manifold edge)
  open,    ///< components with an open boundary
};

using MethodFactory = std::function<std::unique_ptr<CullingMethod>(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options)>;

struct MethodInfo {
  std::string name{};
  /// One line for --help and docs.
  std::string description{};
  MethodNeeds needs{};
  /// Reports fewer contacts than `brute` by design (kept to show what a method misses).
  bool may_miss = false;
  /// Uses MethodOptions::rigid_rows when given (with the intervals' bone transforms): a runner
  /// builds them for such a method when the motion is linear blend skinning.
  bool takes_rigid_rows = false;
  /// Why a run of this method must keep one method object for all its queries under `options`
  /// (its state between queries changes its rows), given whether a DCD query precedes every
  /// CCD interval; empty or unset: blocks of samples may go to several workers with the rows of a
  /// serial run.
  std::function<std::string(const MethodOptions& options, bool dcd_before_each_ccd)>
      serial_reason{};
  /// For a method with a serial_reason: true when what it carries is a function of the pose the
  /// last query ended at, so that a held interval queried after one ending at its pose always
  /// gets the same row (CullingMethod::last_ccd_row_reusable says when that was the case) and the
  /// runner may hand that row on to the next such interval. Unset: false.
  std::function<bool(const MethodOptions& options)> carried_state_follows_pose{};
  /// Where `auto` may route components, and its preference among the methods of that kind whose
  /// needs are met (highest first).
  RouteKind route = RouteKind::none;
  int route_priority = 0;
  /// Boundary loops of up to this many edges the method closes itself (radial view's ghost caps,
  /// skinning::small_simple_loops): `auto` routes an open component whose every hole is such a
  /// loop to it as if it were closed. 0: none.
  std::int32_t closes_holes_up_to = 0;
  /// … in a component with at least this many triangles per side of those loops
  /// (skinning::closing_loops).
  std::int32_t closes_holes_triangles_per_side = 0;
  /// Position in listings (--help, `bench`): ascending, then by name.
  int order = 0;
  MethodFactory make{};
};

/// Adds `info` to the registry. Returns true, so that a module registers a method with
/// `const bool registered = register_method({...});` at namespace scope in its own file.
/// @throws InvalidInput when the name is empty or taken, or `make` is empty.
bool register_method(MethodInfo info);

/// The method called `name`, or null.
[[nodiscard]] const MethodInfo* find_method(std::string_view name);

/// What the method called `name` needs (nothing for an unknown name).
[[nodiscard]] MethodNeeds method_needs(std::string_view name);

/// Every registered method, in listing order.
[[nodiscard]] std::vector<const MethodInfo*> registered_methods();

/// True when a method with `needs` can be built and run with `options` (segmentation given when
/// needed; bone transforms announced by MethodOptions::num_bones when needed).
[[nodiscard]] bool needs_met(const MethodNeeds& needs, const MethodOptions& options);

}  // namespace skelcd::culling
