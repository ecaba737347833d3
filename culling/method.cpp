#include "culling/method.hpp"

#include <cmath>

#include "culling/candidates.hpp"
#include "culling/detail/method_base.hpp"
#include "culling/dual_cone.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/method_registry.hpp"
#include "culling/normal_cone.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace detail {

MethodBase::MethodBase(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    std::shared_ptr<const FeatureTopology> features)
    : name_(name),
      features_(
          features != nullptr ? std::move(features)
                              : shared_or_built(options.features, mesh, topology)),
      topology_(*features_),
      options_(options),
      tests_(with_ccd_defaults(options.elementary)) {
  if (topology_.num_triangles() != topology.welded_triangles.rows()) {
    throw InvalidInput(
        "culling::make_method: the shared feature topology has " +
        std::to_string(topology_.num_triangles()) + " triangles, the topology " +
        std::to_string(topology.welded_triangles.rows()));
  }
  check_method_options(options);
  ccd_options_.min_separation = options.min_separation;
  // The kernels' relative stage (docs/ccd.md, "Relative boxes"): with a contact distance, the
  // relative boxes. Without one its test, nine directions apart at both ends, is the one the
  // feature stage has made on every feature pair it hands over (candidates.hpp, "Each feature
  // pair on the diagonals" in docs/culling.md): it could reject none of them, and is left out.
  ccd_options_.relative_boxes = !feature_stage_tests_ends(options.min_separation);
}

void MethodBase::check_positions(
    const skinning::Positions& x,
    const char* call,
    const char* which) const {
  if (x.rows() != topology_.num_vertices()) {
    throw InvalidInput(
        "culling::" + name_ + "::" + call + ": " + which + " has " + std::to_string(x.rows()) +
        " rows, expected one per welded vertex (" + std::to_string(topology_.num_vertices()) +
        ")");
  }
}

}  // namespace detail

void check_method_options(const MethodOptions& options) {
  if (!std::isfinite(options.min_separation) || options.min_separation < 0.0) {
    throw InvalidInput(
        "culling::make_method: min_separation must be finite and >= 0, got " +
        std::to_string(options.min_separation));
  }
  if (options.accuracy == ccd::Accuracy::exact && options.min_separation > 0.0) {
    throw InvalidInput(
        "culling::make_method: the exact accuracy supports only min_separation = 0, got " +
        std::to_string(options.min_separation));
  }
  if (options.block_pairs == 0) {
    throw InvalidInput("culling::make_method: block_pairs must be >= 1, got 0");
  }
}

std::vector<std::string> method_names() {
  std::vector<std::string> names;
  for (const MethodInfo* m : registered_methods()) names.push_back(m->name);
  return names;
}

std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options) {
  if (const MethodInfo* m = find_method(name)) return m->make(mesh, topology, options);
  std::string known;
  for (const auto& n : method_names()) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown method '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace skelcd::culling
