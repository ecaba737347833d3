#include "clustering/radial_view_methods.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "clustering/ghost_caps.hpp"
#include "clustering/radial_view_method.hpp"
#include "culling/method_registry.hpp"
#include "skinning/errors.hpp"

namespace skelcd::clustering {
namespace {

/// `rvbc` / `dynamic` of a DCD-only run: the same DCD answer as the full method (which hands DCD
/// to its `bvh`), built without the segmentation the full method needs for CCD.
class DcdOnlyRadialViewMethod final : public culling::CullingMethod {
 public:
  DcdOnlyRadialViewMethod(
      std::string name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const culling::MethodOptions& options)
      : name_(std::move(name)), bvh_(culling::make_method("bvh", mesh, topology, options)) {}

  [[nodiscard]] std::string_view name() const override { return name_; }

 protected:
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    bvh_->detect_dcd(at, out);
  }

  void ccd(const culling::Interval&, culling::FrameResult&) override {
    throw InvalidInput(
        "clustering::" + name_ +
        ": built for DCD only (no segmentation); a CCD query needs the full method");
  }

 private:
  std::string name_;
  std::unique_ptr<culling::CullingMethod> bvh_;
};

// What the radial-view methods carry between queries (docs/check.md, "Threads"): which components
// were free of self-intersection at the last interval's end. With a DCD before every interval that
// knowledge is re-established at each start, and the rows do not depend on it.
std::string carried_state(
    std::string_view name, const culling::MethodOptions& options, bool dcd_before_each_ccd) {
  if (options.min_separation != 0.0) return {};
  if (!dcd_before_each_ccd) {
    return "method " + std::string(name) +
           " carries each interval's end state into the next; without the DCD at each sample "
           "(--query ccd) that changes its counters";
  }
  if (options.accuracy == ccd::Accuracy::fast) {
    return "method " + std::string(name) +
           " carries each interval's end state into the next; with --accuracy fast (which may miss "
           "contacts) that can change its rows";
  }
  return {};
}

culling::MethodInfo radial_view_info(
    std::string name, std::string description, int order, culling::RouteKind route) {
  const std::string n = name;
  return culling::MethodInfo{
      .name = std::move(name),
      .description = std::move(description),
      .needs = {.bone_poses = true, .segmentation = true},
      // Its CCD drops the pairs of a certified rigid row (docs/radial-view.md "Rigid rows").
      .takes_rigid_rows = true,
      .serial_reason =
          [n](const culling::MethodOptions& options, bool dcd_before_each_ccd) {
            return carried_state(n, options, dcd_before_each_ccd);
          },
      // What it carries is the set of intersecting pairs at the last interval's end, exact unless
      // `fast` missed a contact; the mega-cluster builder's memory changes its work, never its
      // classes (docs/radial-view.md, "Dynamic mega clusters").
      .carried_state_follows_pose =
          [](const culling::MethodOptions& options) {
            return options.accuracy != ccd::Accuracy::fast;
          },
      .route = route,
      .route_priority = route == culling::RouteKind::closed ? 10 : 0,
      .closes_holes_up_to = kMaxGhostLoop,
      .closes_holes_triangles_per_side = kMinTrianglesPerGhost,
      .order = order,
      .make =
          [n](const skinning::Mesh& mesh,
              const skinning::Topology& topology,
              const culling::MethodOptions& options) {
            return make_radial_view_method(n, mesh, topology, options);
          }};
}

[[maybe_unused]] const bool registered =
    culling::register_method(radial_view_info(
        "rvbc",
        "radial-view culling with fixed atomic clusters (paper 002)",
        70,
        culling::RouteKind::none)) &&
    culling::register_method(radial_view_info(
        "dynamic",
        "radial-view culling with mega clusters merged each interval (paper 002 §5)",
        80,
        culling::RouteKind::closed));

}  // namespace

bool is_radial_view_method(std::string_view name) { return name == "rvbc" || name == "dynamic"; }

std::unique_ptr<culling::CullingMethod> make_radial_view_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const culling::MethodOptions& options,
    std::shared_ptr<const BonePoses> poses) {
  if (!is_radial_view_method(name)) {
    throw InvalidInput(
        "clustering::make_radial_view_method: '" + std::string(name) + "' is not rvbc or dynamic");
  }
  const double gamma = options.parameters.gamma;
  if (!(std::isfinite(gamma) && gamma >= 0.0 && gamma <= 1.0)) {
    throw InvalidInput("clustering: gamma must be in [0, 1], got " + std::to_string(gamma));
  }
  if (!options.segmentation)
    return std::make_unique<DcdOnlyRadialViewMethod>(std::string(name), mesh, topology, options);
  RadialViewOptions rv;
  rv.clusters.merge = name == "dynamic";
  rv.clusters.gamma = gamma;
  rv.clusters.seed = options.parameters.seed;
  return std::make_unique<RadialViewMethod>(
      std::string(name),
      mesh,
      topology,
      options.segmentation,
      std::move(poses),
      options.num_bones,
      options,
      rv);
}

}  // namespace skelcd::clustering
