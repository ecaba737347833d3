#include "culling/method.hpp"

#include <cmath>

#include "culling/detail/method_base.hpp"
#include "culling/dual_cone.hpp"
#include "culling/enhanced_dual_cone.hpp"
#include "culling/method_extension.hpp"
#include "culling/normal_cone.hpp"
#include "culling/routed_method.hpp"
#include "skinning/errors.hpp"

namespace skelcd::culling {
namespace detail {

MethodBase::MethodBase(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options)
    : name_(name),
      topology_(mesh, topology),
      options_(options),
      tests_(with_ccd_defaults(options.elementary)) {
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
  ccd_options_.min_separation = options.min_separation;
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

std::vector<std::string> method_names() {
  return {"brute", "bvh", "kdop", "normal-cone", "dual-cone", "enhanced-dual-cone", "auto"};
}

std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options) {
  if (name == "brute") return detail::make_brute_method(mesh, topology, options);
  if (name == "bvh") return detail::make_bvh_method<3>(name, mesh, topology, options);
  if (name == "kdop") return detail::make_bvh_method<8>(name, mesh, topology, options);
  if (name == "normal-cone") return make_normal_cone_method(mesh, topology, options);
  if (name == "dual-cone") return make_dual_cone_method(mesh, topology, options);
  if (name == "enhanced-dual-cone") return make_enhanced_dual_cone_method(mesh, topology, options);
  if (name == "auto") return make_routed_method(mesh, topology, options);
  if (options.extension) {
    if (auto m = options.extension->make_method(name, mesh, topology, options)) return m;
  }
  std::string known;
  for (const auto& n : method_names(options)) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInput("unknown method '" + std::string(name) + "' (known: " + known + ")");
}

}  // namespace skelcd::culling
