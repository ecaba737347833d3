// `normal-cone` (NCT for DCD, CBC for CCD) on the shared cone engine.
#include "culling/normal_cone.hpp"

#include "culling/cones_method_base.hpp"

namespace skelcd::culling {
namespace {

class NormalConeMethod final : public detail::ConeMethodBase {
 public:
  NormalConeMethod(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      const std::vector<std::int32_t>* subset,
      std::shared_ptr<const FeatureTopology> features = {})
      : ConeMethodBase(
            "normal-cone",
            mesh,
            topology,
            options,
            Descent::children,
            /*needs_contours=*/true,
            subset,
            std::move(features)) {}

 private:
  bool node_culled(std::int32_t n, const Interval& interval) override {
    const ContourStatus status = contours_.status(n);
    if (status == ContourStatus::not_tested) return false;  // two leaves: one pair test is cheaper
    ++stats_.nodes_tested;
    // Surface normal test (continuous normal cone for CCD).
    Eigen::Vector3d axis;
    if (!normal_test(n, axis)) {
      ++stats_.failed_normal_cone;
      return false;
    }
    if (status != ContourStatus::loops) {
      ++stats_.failed_topology;
      return false;
    }
    // Contour test: the whole projected loop simple (continuous contour test for CCD).
    const ContourVerdict verdict =
        interval.continuous
            ? contour_tester_.test(
                  contours_,
                  n,
                  axis,
                  *interval.x_t0,
                  *interval.x_t1,
                  ContourMode::every_edge,
                  stats_.contour)
            : contour_tester_.test(
                  contours_, n, axis, *interval.x_t0, ContourMode::every_edge, stats_.contour);
    if (verdict.simple) return true;
    ++stats_.failed_contour;
    return false;
  }
};

}  // namespace

std::unique_ptr<CullingMethod> make_normal_cone_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options) {
  return std::make_unique<NormalConeMethod>(mesh, topology, options, nullptr);
}

std::unique_ptr<CullingMethod> make_normal_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles,
    std::shared_ptr<const FeatureTopology> features) {
  return std::make_unique<NormalConeMethod>(
      mesh, topology, options, &triangles, std::move(features));
}

}  // namespace skelcd::culling
