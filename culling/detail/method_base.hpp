#pragma once
// What every culling method holds: the mesh's features, the options, the bound elementary tests,
// and the checks and clock shared by the implementations. Internal to culling/.

#include <chrono>
#include <memory>
#include <string>
#include <string_view>

#include "culling/feature_topology.hpp"
#include "culling/method.hpp"

namespace skelcd::culling::detail {

class MethodBase : public CullingMethod {
 public:
  [[nodiscard]] std::string_view name() const override { return name_; }

  /// The method's feature topology, which another method of the same mesh and topology may share
  /// (`auto` lends its own to its cone group methods: docs/culling.md "Bounded memory").
  [[nodiscard]] std::shared_ptr<const FeatureTopology> shared_features() const override {
    return features_;
  }

 protected:
  /// @param features when not null, a FeatureTopology(mesh, topology) another method built, used
  ///        instead of building another one; when null, shared_or_built(options.features, …).
  /// @throws InvalidInput for bad options, or features of another triangle count.
  MethodBase(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      std::shared_ptr<const FeatureTopology> features = {});

  /// @throws InvalidInput when `x` does not have one row per welded vertex.
  void check_positions(const skinning::Positions& x, const char* call, const char* which) const;

  using Clock = std::chrono::steady_clock;
  [[nodiscard]] static double micros(Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double, std::micro>(to - from).count();
  }

  std::string name_;
  std::shared_ptr<const FeatureTopology> features_;  ///< built here or lent by another method
  const FeatureTopology& topology_;                  ///< *features_
  MethodOptions options_;
  ElementaryTests tests_;
  ccd::CcdOptions ccd_options_;
};

[[nodiscard]] std::unique_ptr<CullingMethod> make_brute_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options);

/// `bvh` (N = 3) and `kdop` (N = 8). With `relative_pairs` a CCD query also sends its triangle
/// pairs through the relative AABB filter (culling/relative_aabb.hpp) whenever a trial on its first
/// pairs shows that it pays (docs/culling.md "Relative boxes in `kdop`"). With `rigid_rows` its
/// CCD skips the pairs of certified rows of MethodOptions::rigid_rows when given (docs/culling.md
/// "Rigid rows"): `kdop`, and `auto`'s `bvh` for a whole mesh; never the `bvh` method itself.
template <int N>
[[nodiscard]] std::unique_ptr<CullingMethod> make_bvh_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    bool relative_pairs = false,
    bool rigid_rows = false);

}  // namespace skelcd::culling::detail
