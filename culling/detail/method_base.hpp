#pragma once
// What every culling method holds: the mesh's features, the options, the bound elementary tests,
// and the checks and clock shared by the implementations. Internal to culling/.

#include <chrono>
#include <string>
#include <string_view>

#include "culling/feature_topology.hpp"
#include "culling/method.hpp"

namespace skelcd::culling::detail {

class MethodBase : public CullingMethod {
 public:
  [[nodiscard]] std::string_view name() const override { return name_; }

 protected:
  MethodBase(
      std::string_view name,
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options);

  /// @throws InvalidInput when `x` does not have one row per welded vertex.
  void check_positions(const skinning::Positions& x, const char* call, const char* which) const;

  using Clock = std::chrono::steady_clock;
  [[nodiscard]] static double micros(Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double, std::micro>(to - from).count();
  }

  std::string name_;
  FeatureTopology topology_;
  MethodOptions options_;
  ElementaryTests tests_;
  ccd::CcdOptions ccd_options_;
};

[[nodiscard]] std::unique_ptr<CullingMethod> make_brute_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options);

/// `bvh` (N = 3) and `kdop` (N = 8).
template <int N>
[[nodiscard]] std::unique_ptr<CullingMethod> make_bvh_method(
    std::string_view name,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options);

}  // namespace skelcd::culling::detail
