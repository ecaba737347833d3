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
      const std::vector<std::int32_t>* subset)
      : ConeMethodBase(
            "enhanced-dual-cone", mesh, topology, options, Descent::grandchildren,
            /*needs_contours=*/true, subset) {}

 private:
  // EnhancedDualConeTest (Algorithms 1 and 4) of node n.
  bool node_culled(std::int32_t n, const Interval& interval) override {
    const ContourStatus status = contours_.status(n);
    if (status == ContourStatus::not_tested) return false;  // children are leaves: standard tests
    ++stats_.nodes_tested;
    // Condition 1: θ_n < π/2 — every (continuous) normal of the node has n · A_n > 0.
    const DirectionCone& snc = cones_.node_cones()[static_cast<std::size_t>(n)];
    if (!snc.in_open_half_space()) {
      ++stats_.failed_normal_cone;
      return false;
    }
    // The degree argument behind conditions 2 and 3 needs one simple loop of contour.
    if (status != ContourStatus::loops) {
      ++stats_.failed_topology;
      return false;
    }
    // Conditions 2 and 3, projected along A_n.
    const ContourVerdict verdict =
        interval.continuous
            ? contour_tester_.test(
                  contours_, n, snc.axis, *interval.x_t0, *interval.x_t1, ContourMode::chains,
                  stats_.contour)
            : contour_tester_.test(
                  contours_, n, snc.axis, *interval.x_t0, ContourMode::chains, stats_.contour);
    if (verdict.simple) return true;
    if (verdict.failed_chain) {
      ++stats_.failed_dual_cone;
      if (verdict.part_a >= 0) ++stats_.ten_results_failed[static_cast<std::size_t>(verdict.part_a)];
    } else {
      ++stats_.failed_contour;
      const int p = std::min(verdict.part_a, verdict.part_b);
      const int q = std::max(verdict.part_a, verdict.part_b);
      // Two chains of one sub-surface meeting fail that sub-surface's own test.
      const int index = p == q ? p : ten_result_pair_index(p, q);
      if (p >= 0) ++stats_.ten_results_failed[static_cast<std::size_t>(index)];
    }
    return false;
  }
};

}  // namespace

std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options) {
  return std::make_unique<EnhancedDualConeMethod>(mesh, topology, options, nullptr);
}

std::unique_ptr<CullingMethod> make_enhanced_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles) {
  return std::make_unique<EnhancedDualConeMethod>(mesh, topology, options, &triangles);
}

}  // namespace skelcd::culling
