#include "skinning/lbs.hpp"

#include <cassert>
#include <vector>

namespace skelcd::skinning {

namespace {

/// out.row(k) = the skinned position of vertex vertex_of(k), k < rows: the one kernel of
/// linear_blend_skinning and linear_blend_skinning_rows.
template <typename VertexOf>
void skin_rows(
    const Positions& rest_positions,
    const SkinWeights& weights,
    std::span<const BoneTransform> transforms,
    Eigen::Index rows,
    const VertexOf& vertex_of,
    Positions& out) {
  assert(weights.rows() == rest_positions.rows());
  assert(static_cast<std::size_t>(weights.cols()) <= transforms.size());
  assert(&out != &rest_positions);
  if (out.rows() != rows) out.resize(rows, 3);
  // Blend the transforms of a vertex's influences into one 3 × 4 matrix, then apply it once:
  // 12 multiply-adds per influence plus one matrix-vector product per vertex.
  const auto* outer = weights.outerIndexPtr();
  const auto* inner = weights.innerIndexPtr();
  const auto* value = weights.valuePtr();
  const auto* nnz = weights.innerNonZeroPtr();  // null when compressed
  for (Eigen::Index k = 0; k < rows; ++k) {
    const Eigen::Index v = vertex_of(k);
    const auto begin = outer[v];
    const auto end = nnz ? begin + nnz[v] : outer[v + 1];
    if (begin == end) {
      out.row(k) = rest_positions.row(v);
      continue;
    }
    BoneTransform blended = value[begin] * transforms[static_cast<std::size_t>(inner[begin])];
    for (auto i = begin + 1; i < end; ++i) {
      blended.noalias() += value[i] * transforms[static_cast<std::size_t>(inner[i])];
    }
    const Eigen::Vector3d p = rest_positions.row(v).transpose();
    out.row(k).noalias() = (blended.leftCols<3>() * p + blended.col(3)).transpose();
  }
}

}  // namespace

void linear_blend_skinning(
    const Positions& rest_positions,
    const SkinWeights& weights,
    std::span<const BoneTransform> transforms,
    Positions& out) {
  skin_rows(
      rest_positions,
      weights,
      transforms,
      rest_positions.rows(),
      [](Eigen::Index k) { return k; },
      out);
}

void linear_blend_skinning_rows(
    const Positions& rest_positions,
    const SkinWeights& weights,
    std::span<const BoneTransform> transforms,
    std::span<const std::int32_t> vertices,
    Positions& out) {
  skin_rows(
      rest_positions,
      weights,
      transforms,
      static_cast<Eigen::Index>(vertices.size()),
      [vertices](Eigen::Index k) {
        const std::int32_t v = vertices[static_cast<std::size_t>(k)];
        assert(v >= 0);
        return static_cast<Eigen::Index>(v);
      },
      out);
}

LinearBlendSkinning::LinearBlendSkinning(const Rig& rig) : rig_(&rig) {
  const auto nv = rig.mesh.num_vertices();
  const auto nb = rig.skeleton.num_bones();
  const auto np = rig.mesh.num_parts();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<std::size_t>(rig.weights.nonZeros()) + static_cast<std::size_t>(nv));
  for (Eigen::Index v = 0; v < nv; ++v) {
    bool any = false;
    if (v < rig.weights.rows()) {
      for (SkinWeights::InnerIterator it(rig.weights, v); it; ++it) {
        entries.emplace_back(static_cast<int>(v), static_cast<int>(it.col()), it.value());
        any = true;
      }
    }
    if (!any) {
      const auto part = rig.mesh.vertex_part[static_cast<std::size_t>(v)];
      entries.emplace_back(static_cast<int>(v), static_cast<int>(nb + part), 1.0);
    }
  }
  weights_.resize(nv, nb + np);
  weights_.setFromTriplets(entries.begin(), entries.end());
  weights_.makeCompressed();
}

void LinearBlendSkinning::apply(const Pose& pose, Positions& out) const {
  assert(pose.transforms.size() == static_cast<std::size_t>(weights_.cols()));
  linear_blend_skinning(rig_->mesh.rest_positions, weights_, pose.transforms, out);
}

void LinearBlendSkinning::apply_rows(
    const Pose& pose, std::span<const std::int32_t> vertices, Positions& out) const {
  assert(pose.transforms.size() == static_cast<std::size_t>(weights_.cols()));
  linear_blend_skinning_rows(rig_->mesh.rest_positions, weights_, pose.transforms, vertices, out);
}

}  // namespace skelcd::skinning
