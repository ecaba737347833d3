// `dual-cone` (FASTCD) on the shared cone engine: binormal cones of the original boundary edges,
// merged bottom-up with the normal cones, and the Dual-Cone Theorem as the node test.
#include "culling/dual_cone.hpp"

#include <cmath>

#include "culling/cones_method_base.hpp"

namespace skelcd::culling {
namespace {

class DualConeMethod final : public detail::ConeMethodBase {
 public:
  DualConeMethod(
      const skinning::Mesh& mesh,
      const skinning::Topology& topology,
      const MethodOptions& options,
      const std::vector<std::int32_t>* subset,
      std::shared_ptr<const FeatureTopology> features = {})
      : ConeMethodBase(
            "dual-cone",
            mesh,
            topology,
            options,
            Descent::children,
            /*needs_contours=*/false,
            subset,
            std::move(features)) {
    // Which sides of each triangle are boundary edges of the mesh (one incident face).
    const auto nf = static_cast<std::size_t>(topology_.num_triangles());
    boundary_sides_.assign(nf, 0);
    for (std::int32_t f = 0; f < topology_.num_triangles(); ++f) {
      for (int k = 0; k < 3; ++k) {
        const std::int32_t side = topology_.face_edge(f, k);
        if (side < 0) continue;  // a collapsed side of a degenerate triangle
        const auto e = static_cast<std::size_t>(side);
        if (e + 1 < topology.edge_face_offsets.size() &&
            topology.edge_face_offsets[e + 1] - topology.edge_face_offsets[e] == 1) {
          boundary_sides_[static_cast<std::size_t>(f)] |= static_cast<std::uint8_t>(1u << k);
        }
      }
    }
    triangle_bnc_.resize(nf);
    node_bnc_.resize(bvh_.nodes().size());
  }

 private:
  void refit_extra(const Interval& interval) override {
    const auto& x0 = *interval.x_t0;
    const auto& x1 = *interval.x_t1;
    for (std::int32_t f = 0; f < topology_.num_triangles(); ++f) {
      const auto uf = static_cast<std::size_t>(f);
      DirectionCone bnc = DirectionCone::empty_cone();
      if (boundary_sides_[uf] != 0) {
        const auto& t = topology_.triangle(f);
        std::array<Eigen::Vector3d, 3> p0;
        std::array<Eigen::Vector3d, 3> p1;
        for (std::size_t k = 0; k < 3; ++k) {
          p0[k] = x0.row(t[k]).transpose();
          p1[k] = x1.row(t[k]).transpose();
        }
        bnc = boundary_binormal_cone(p0, p1, boundary_sides_[uf], interval.continuous);
      }
      triangle_bnc_[uf] = bnc;
    }
    const auto nodes = bvh_.nodes();
    const auto order = bvh_.triangle_order();
    for (std::size_t i = nodes.size(); i-- > 0;) {
      const BvhNode& node = nodes[i];
      if (node.is_leaf()) {
        DirectionCone bnc = DirectionCone::empty_cone();
        for (std::int32_t s = node.begin; s < node.end; ++s) {
          bnc = merge(
              bnc, triangle_bnc_[static_cast<std::size_t>(order[static_cast<std::size_t>(s)])]);
        }
        node_bnc_[i] = bnc;
      } else {
        node_bnc_[i] = merge(node_bnc_[i + 1], node_bnc_[static_cast<std::size_t>(node.right)]);
      }
    }
  }

  // The Dual-Cone Theorem at node n (FASTCD): θ_n < π/2 and |A_n · A_b| < cos θ_b.
  bool node_culled(std::int32_t n, const Interval& /*interval*/) override {
    ++stats_.nodes_tested;
    const DirectionCone snc = cones_.node_cone(bvh_, n);
    if (!snc.in_open_half_space()) {
      ++stats_.failed_normal_cone;
      return false;
    }
    const DirectionCone& bnc = node_bnc_[static_cast<std::size_t>(n)];
    if (bnc.is_empty()) return true;  // no original boundary edge: the internal ones are ignored
    if (bnc.is_full() || !(std::abs(snc.axis.dot(bnc.axis)) < bnc.cos_angle)) {
      ++stats_.failed_dual_cone;
      return false;
    }
    return true;
  }

  std::vector<std::uint8_t> boundary_sides_;
  std::vector<DirectionCone> triangle_bnc_;
  std::vector<DirectionCone> node_bnc_;
};

}  // namespace

std::unique_ptr<CullingMethod> make_dual_cone_method(
    const skinning::Mesh& mesh, const skinning::Topology& topology, const MethodOptions& options) {
  return std::make_unique<DualConeMethod>(mesh, topology, options, nullptr);
}

std::unique_ptr<CullingMethod> make_dual_cone_method(
    const skinning::Mesh& mesh,
    const skinning::Topology& topology,
    const MethodOptions& options,
    const std::vector<std::int32_t>& triangles,
    std::shared_ptr<const FeatureTopology> features) {
  return std::make_unique<DualConeMethod>(mesh, topology, options, &triangles, std::move(features));
}

}  // namespace skelcd::culling
