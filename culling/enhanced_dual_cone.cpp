// `enhanced-dual-cone`: Algorithms 1–4 of paper 000 on the shared cone engine.
#include "culling/enhanced_dual_cone.hpp"

#include "culling/cones_method_base.hpp"

namespace skelcd::culling {
namespace {

class EnhancedDualConeMethod final : public detail::ConeMethodBase {
 public:
  EnhancedDualConeMethod(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      const EnhancedDualConeOptions& variant)
      : ConeMethodBase(
            "enhanced-dual-cone",
            mesh,
            topology,
            options,
            variant.grandchildren_descent ? Descent::grandchildren : Descent::children,
            /*needs_contours=*/true,
            variant.triangles.empty() ? nullptr : &variant.triangles,
            variant.features) {}

 private:
  // EnhancedDualConeTest (Algorithms 1 and 4) of node n.
  bool node_culled(std::int32_t n, const Interval& interval) override {
    const ContourStatus status = contours_.status(n);
    if (status == ContourStatus::not_tested) return false;  // children are leaves: standard tests
    ++stats_.nodes_tested;
    // Condition 1: θ_n < π/2 — every (continuous) normal of the node has n · A_n > 0.
    Eigen::Vector3d axis;
    if (!normal_test(n, axis)) {
      ++stats_.failed_normal_cone;
      return false;
    }
    // The degree argument behind conditions 2 and 3 needs the contour to be closed loops.
    if (status != ContourStatus::loops) {
      ++stats_.failed_topology;
      return false;
    }
    // Conditions 2 and 3, projected along A_n.
    const ContourVerdict verdict =
        interval.continuous
            ? contour_tester_.test(
                  contours_,
                  n,
                  axis,
                  *interval.x_t0,
                  *interval.x_t1,
                  ContourMode::chains,
                  stats_.contour)
            : contour_tester_.test(
                  contours_, n, axis, *interval.x_t0, ContourMode::chains, stats_.contour);
    // The ten-result record (Algorithm 3): the sub-surfaces whose chains failed the dual-cone
    // test, and the first pair of sub-surfaces whose contours may meet.
    for (int p = 0; p < 4; ++p) {
      if ((verdict.cut_parts & (1u << p)) != 0)
        ++stats_.ten_results_failed[static_cast<std::size_t>(p)];
    }
    if (verdict.simple) return true;
    ++(verdict.cut_parts != 0 ? stats_.failed_dual_cone : stats_.failed_contour);
    if (verdict.part_a >= 0 && verdict.part_b >= 0) {
      const int p = std::min(verdict.part_a, verdict.part_b);
      const int q = std::max(verdict.part_a, verdict.part_b);
      // Two chains of one sub-surface meeting fail that sub-surface's own test.
      ++stats_
            .ten_results_failed[static_cast<std::size_t>(p == q ? p : ten_result_pair_index(p, q))];
    }
    return false;
  }
};

}  // namespace

std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options) {
  return std::make_unique<EnhancedDualConeMethod>(
      mesh, topology, options, EnhancedDualConeOptions{});
}

std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const EnhancedDualConeOptions& variant) {
  return std::make_unique<EnhancedDualConeMethod>(mesh, topology, options, variant);
}

}  // namespace skelcd::culling
