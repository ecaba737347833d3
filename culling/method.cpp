#include "culling/method.hpp"

#include "skinning/errors.hpp"

namespace skelcd::culling {

std::vector<std::string> method_names() { return {}; }

std::unique_ptr<CullingMethod> make_method(
    std::string_view name,
    const skinning::Mesh& /*mesh*/,
    const skinning::Topology& /*topology*/,
    const MethodOptions& /*options*/) {
  throw InvalidInput("unknown method '" + std::string(name) + "'");
}

}  // namespace skelcd::culling
