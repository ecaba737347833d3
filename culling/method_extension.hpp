#pragma once
// Methods built above culling/: modules that culling/ must not depend on (clustering's radial-view
// methods `rvbc` and `dynamic`, DESIGN.md "Modules") implement this interface, and a caller that
// has what those methods need (a segmentation, bone poses) puts one into
// MethodOptions::extension. make_method then builds the extension's names as if they were its own,
// and anything that forwards its MethodOptions (a routed method building `dynamic` for the closed
// parts) reaches them too. No global registry: what an extension method needs travels with the
// options that name it.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "culling/method.hpp"
#include "skinning/mesh.hpp"
#include "skinning/topology.hpp"

namespace skelcd::culling {

class MethodExtension {
 public:
  virtual ~MethodExtension() = default;

  /// The method names this extension builds, in the order `bench` should list them.
  [[nodiscard]] virtual std::vector<std::string> method_names() const = 0;

  /// Builds method `name`, or returns null when `name` is not one of method_names().
  /// @param options the options make_method was given (this extension among them).
  /// @throws InvalidInput as make_method does, and when the extension's data do not fit `mesh`.
  [[nodiscard]] virtual std::unique_ptr<CullingMethod> make_method(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options) const = 0;
};

/// method_names() followed by the names of options.extension (when set).
[[nodiscard]] inline std::vector<std::string> method_names(const MethodOptions& options) {
  std::vector<std::string> names = method_names();
  if (options.extension) {
    for (auto& n : options.extension->method_names()) names.push_back(std::move(n));
  }
  return names;
}

}  // namespace skelcd::culling
