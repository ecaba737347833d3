#pragma once
// The plan of a scene: for every object which stages run (and why the others do not), for every
// check what it asks. Made before any check runs and printed first (docs/scenes.md, "The plan").
// Rule: nothing that no requested check needs is built or run.

#include <cstdint>
#include <string>
#include <vector>

#include "tools/engine/scene.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

/// What loading taught about an object (zeros for an object that was not loaded).
struct ObjectFacts {
  std::string source;  ///< what was loaded: file, spec, "sheet attached to X"
  std::string motion;  ///< clip / trajectory / sequence name
  std::int32_t samples = 0;
  double rate_hz = 0;
  std::int64_t vertices = 0;
  std::int64_t triangles = 0;
  std::int32_t parts = 0;
  std::int32_t open_components = 0;  ///< edge-connected components with a boundary
  std::int32_t closed_components = 0;
  bool rig_motion = false;  ///< moved by its own skeleton (the radial-view methods need that)
  /// Every component closed, under 256 triangles or open only at holes the radial view would cap:
  /// `auto` sends the whole mesh to `bvh`
  /// (culling::routes_whole_mesh_to_all_closed_method), with no cones and no segmentation.
  bool auto_whole_to_bvh = false;
  /// Components `auto` would give its cone method (open, 256 triangles or more, not capped) and
  /// its closed-part method (the others) on this object's motion (culling::auto_groups): the
  /// cones run only for the first, a segmentation is made only for the second.
  std::int32_t auto_open_group = 0;
  std::int32_t auto_closed_group = 0;
};

struct ObjectPlan {
  std::string name;
  int line = 0;
  bool checked = false;  ///< some check names it
  bool self_dcd = false;
  bool self_ccd = false;
  bool pair_dcd = false;
  bool pair_ccd = false;
  std::string method;  ///< of its self check
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  // Stages.
  bool load = false;          ///< read and imported (checked objects and attach targets)
  bool skin = false;          ///< posed sample by sample
  bool topology = false;      ///< welded topology (+ feature ownership)
  bool bvh = false;           ///< a hierarchy, refit per query
  bool swept_bounds = false;  ///< swept volumes over intervals (CCD)
  bool cones = false;         ///< normal / dual cones (cone methods; `auto`: open parts only)
  bool segmentation =
      false;  ///< atomic clusters (rvbc, dynamic; `auto` with closed parts of a rig)
  /// One line per stage left out of a loaded object, saying why.
  std::vector<std::string> skipped;
  ObjectFacts facts;
};

enum class CheckKind : std::uint8_t { self, pair };

struct CheckPlan {
  CheckKind kind = CheckKind::self;
  std::int32_t object_a = -1;  ///< index into ScenePlan::objects
  std::int32_t object_b = -1;  ///< pairs only
  QuerySet query = QuerySet::both;
  std::string method;  ///< self: the object's; pair: "bvh" (pair traversal)
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  int line = 0;
  std::int32_t first_sample = 0;
  std::int32_t last_sample = 0;
  std::int64_t rows = 0;
  /// "self body", "pair body cape".
  [[nodiscard]] std::string name(const std::vector<ObjectPlan>& objects) const;
};

struct ScenePlan {
  std::string scene;                ///< the scene file
  std::vector<ObjectPlan> objects;  ///< scene order
  std::vector<CheckPlan> checks;    ///< self checks in object order, then pairs in file order
  std::int64_t rows = 0;            ///< /frames rows of the whole run
};

/// Objects the run loads: every checked object and every object a checked sheet is attached to.
[[nodiscard]] std::vector<bool> objects_to_load(const Scene& scene);

/// The plan of `scene`, given what loading taught (facts[i] for scene.objects[i]; zeros for
/// objects not loaded) and the frame range (scene's or the command line's).
/// @throws InvalidInput "SCENE:LINE: …" when a check's frame range does not fit its samples.
[[nodiscard]] ScenePlan plan_scene(
    const Scene& scene,
    const std::vector<ObjectFacts>& facts,
    const std::optional<FrameRange>& frames);

}  // namespace skelcd::tools
