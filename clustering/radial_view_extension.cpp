#include "clustering/radial_view_extension.hpp"

#include <cmath>
#include <utility>

#include "skinning/errors.hpp"

namespace skelcd::clustering {

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
  if (!(std::isfinite(parameters.gamma) && parameters.gamma >= 0.0 && parameters.gamma <= 1.0)) {
    throw InvalidInput(
        "clustering: gamma must be in [0, 1], got " + std::to_string(parameters.gamma));
  }
}

std::vector<std::string> RadialViewExtension::method_names() const { return {"rvbc", "dynamic"}; }

std::unique_ptr<culling::CullingMethod> RadialViewExtension::make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const culling::MethodOptions& options) const {
  if (!is_radial_view_method(name)) return nullptr;
  RadialViewOptions rv;
  rv.clusters.merge = name == "dynamic";
  rv.clusters.gamma = parameters_.gamma;
  rv.clusters.seed = parameters_.seed;
  return std::make_unique<RadialViewMethod>(std::string(name), mesh, topology, segmentation_,
                                            poses_, num_bones_, options, rv);
}

}  // namespace skelcd::clustering
