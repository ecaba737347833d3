#pragma once
// What `check` (and any command built on ClipRunner) adds for the radial-view methods `rvbc` and
// `dynamic`: the options --gamma, --seed, --segmentation, and the setup that gives the runner's
// method what it needs beyond the mesh — a segmentation (read from a `preprocess` file made from
// the same model, else computed from the rig); the bone poses of each interval travel with the
// query (docs/radial-view.md, "Command line").

#include <cstdint>
#include <optional>
#include <string>

#include "skinning/load.hpp"
#include "skinning/motion.hpp"
#include "tools/engine/runner.hpp"

namespace skelcd::tools {

struct RadialViewArguments {
  double gamma = 0.05;  ///< merge threshold γ of `dynamic` (§5)
  std::uint64_t seed = 1;
  std::string segmentation;  ///< SEG.h5 from `skelcd preprocess`; empty: computed here
};

struct RadialViewSetup {
  /// Where the segmentation came from: the file, or "computed (rig weights)" / "(heat weights)".
  std::string segmentation_source;
  std::int32_t atomic_clusters = 0;
  /// γ and the seed when the method uses them (`dynamic`), for the log header.
  std::optional<double> gamma;
  std::optional<std::int64_t> seed;
};

/// For a method that needs a segmentation (rvbc, dynamic; `auto` on a rig's clip): loads or
/// computes it and sets options.segmentation and options.method_parameters; the bones'
/// transforms then travel with every query (the runner asks the motion for them). With
/// options.query == dcd nothing of the radial view is built: rvbc/dynamic answer DCD as `bvh`
/// does and `auto`'s closed parts go to its `bvh` fallback. Does nothing and returns an empty
/// setup for any other method.
/// @param motion the motion the runner will check (a rig's clip: Motion::num_bones() > 0).
/// @param topology when given, `skinning::build_topology(motion.mesh())`: the segmentation
///   computed here uses it instead of welding the rig's mesh again (when the motion moves that
///   very mesh).
/// @throws InvalidInput when the model has no rig, the motion is not a rig's, γ is outside
///   [0, 1], or the segmentation file was made from another model (hash mismatch); IoError when
///   the segmentation file cannot be read.
[[nodiscard]] RadialViewSetup setup_radial_view(
    const RadialViewArguments& args,
    const skinning::LoadedModel& model,
    const skinning::Motion& motion,
    RunOptions& options,
    const skinning::Topology* topology = nullptr);

/// Why `auto` on a rig's clip makes no segmentation for this mesh, when it makes none: it sends
/// the whole mesh to `bvh` (every part closed, small or capped, under the whole-mesh size), or
/// every part to the cones (each open, of 256 triangles or more, not capped), so that no group
/// goes to `dynamic` (culling::auto_groups with the rig's closed method).
struct AutoWithoutSegmentation {
  std::string source;  ///< the summary's `segmentation` value, "none (auto: …)"
  std::string why;     ///< why a --segmentation file given is not read
};

/// What auto_groups(topology, rig) says of the segmentation, as setup_radial_view decides it for
/// `auto` (also `bench`, so that its `auto` runs as `check`'s); nothing when a closed group goes
/// to `dynamic`.
/// @param topology `skinning::build_topology` of the mesh the motion moves.
[[nodiscard]] std::optional<AutoWithoutSegmentation> auto_without_segmentation(
    const skinning::Topology& topology);

/// "under N triangles": the size below which `auto` sends a mesh closed, small or capped
/// throughout whole to `bvh` (culling::RoutingOptions::all_closed_below_triangles), as the
/// messages that say so put it.
[[nodiscard]] std::string auto_whole_mesh_size();

/// "N triangles": the size from which `auto` gives an open part that dynamic does not cap to its
/// cone method (culling::RoutingOptions::min_open_triangles), as the messages that say so put it.
[[nodiscard]] std::string auto_open_size();

}  // namespace skelcd::tools
