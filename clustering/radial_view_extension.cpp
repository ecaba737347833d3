#include "clustering/radial_view_extension.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "culling/method.hpp"
#include "skinning/errors.hpp"

namespace skelcd::clustering {
namespace {

void check_gamma(double gamma) {
  if (!(std::isfinite(gamma) && gamma >= 0.0 && gamma <= 1.0)) {
    throw InvalidInput("clustering: gamma must be in [0, 1], got " + std::to_string(gamma));
  }
}

/// `rvbc` / `dynamic` of a DCD-only run: the same DCD answer as the full method (which hands DCD
/// to its `bvh`), built without the segmentation the full method needs for CCD.
class DcdOnlyRadialViewMethod final : public culling::CullingMethod {
 public:
  DcdOnlyRadialViewMethod(
      std::string name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      culling::MethodOptions options)
      : name_(std::move(name)), bvh_([&] {
          options.extension = nullptr;
          return culling::make_method("bvh", mesh, topology, options);
        }()) {}

  [[nodiscard]] std::string_view name() const override { return name_; }

  void detect_dcd(const skinning::Positions& x, culling::FrameResult& out) override {
    bvh_->detect_dcd(x, out);
  }

  void detect_ccd(
      const skinning::Positions&, const skinning::Positions&, culling::FrameResult&) override {
    throw InvalidInput(
        "clustering::" + name_ +
        ": built for DCD only (no segmentation); a CCD query needs the full method");
  }

 private:
  std::string name_;
  std::unique_ptr<culling::CullingMethod> bvh_;
};

}  // namespace

bool is_radial_view_method(std::string_view name) { return name == "rvbc" || name == "dynamic"; }

RadialViewExtension::RadialViewExtension(
    std::shared_ptr<const segmentation::Segmentation> segmentation,
    std::shared_ptr<const BonePoses> poses,
    std::int32_t num_bones,
    const RadialViewParameters& parameters)
    : segmentation_(std::move(segmentation)),
      poses_(std::move(poses)),
      num_bones_(num_bones),
      parameters_(parameters) {
  if (!segmentation_ || !poses_) {
    throw InvalidInput("clustering::RadialViewExtension: a segmentation and bone poses are needed");
  }
  check_gamma(parameters.gamma);
}

RadialViewExtension::RadialViewExtension(const RadialViewParameters& parameters)
    : num_bones_(0), parameters_(parameters) {
  check_gamma(parameters.gamma);
}

std::shared_ptr<const RadialViewExtension> RadialViewExtension::dcd_only(
    const RadialViewParameters& parameters) {
  return std::shared_ptr<const RadialViewExtension>(new RadialViewExtension(parameters));
}

std::vector<std::string> RadialViewExtension::method_names() const { return {"rvbc", "dynamic"}; }

std::unique_ptr<culling::CullingMethod> RadialViewExtension::make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const culling::MethodOptions& options) const {
  if (!is_radial_view_method(name)) return nullptr;
  if (is_dcd_only()) {
    return std::make_unique<DcdOnlyRadialViewMethod>(std::string(name), mesh, topology, options);
  }
  RadialViewOptions rv;
  rv.clusters.merge = name == "dynamic";
  rv.clusters.gamma = parameters_.gamma;
  rv.clusters.seed = parameters_.seed;
  return std::make_unique<RadialViewMethod>(std::string(name), mesh, topology, segmentation_,
                                            poses_, num_bones_, options, rv);
}

}  // namespace skelcd::clustering
