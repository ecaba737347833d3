// Cloth: an open sheet on a row of hinge bones that folds its right part over onto its left part.
//
// The sheet is [0, 2] × [0, 1] in the plane z = 0, a grid of nx × ny squares each split into two
// triangles. Bone 0 holds x in [0, 1] and never moves; six hinge bones of 0.0259 follow (joints
// turning about −y, so +x lifts), and the last bone holds the right part x in [1.155, 2] rigidly.
// At 180° the right part lies flat 0.1 above the left one; beyond it, it tilts down until its free
// edge (x = 2 at rest) lands on the left part near x = 0.15.

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "skinning/generators_common.hpp"

namespace skelcd::skinning::generators {

GeneratedRig generate_cloth(std::int64_t triangles, int frames) {
  constexpr double kPi = std::numbers::pi;
  constexpr double kWidth = 2.0;
  constexpr double kHeight = 1.0;
  constexpr double kStart = 1.0;
  constexpr int kHingeBones = 6;
  constexpr double kBlend = 1.0;
  const double hinge_bone = 0.1 * std::sin(15.0 * kPi / 180.0);  // hinge radius 0.05 at 30° per joint
  const double end_joint = kStart + kHingeBones * hinge_bone;
  const double turn_end = 36.0 * kPi / 180.0;

  // 2 · nx · ny triangles with square cells: ny = sqrt(T / 4), nx = T / (2 ny).
  const std::int64_t ny = round_at_least(std::sqrt(static_cast<double>(triangles) / 4.0), 1);
  const std::int64_t nx = round_at_least(static_cast<double>(triangles) / (2.0 * static_cast<double>(ny)), 1);

  MeshBuilder mesh;
  std::vector<double> vertex_x;
  const auto id = [&](std::int64_t i, std::int64_t j) { return static_cast<std::int32_t>(i * (ny + 1) + j); };
  for (std::int64_t i = 0; i <= nx; ++i) {
    const double x = kWidth * static_cast<double>(i) / static_cast<double>(nx);
    for (std::int64_t j = 0; j <= ny; ++j) {
      mesh.add({x, kHeight * static_cast<double>(j) / static_cast<double>(ny), 0.0});
      vertex_x.push_back(x);
    }
  }
  for (std::int64_t i = 0; i < nx; ++i) {
    for (std::int64_t j = 0; j < ny; ++j) mesh.quad(id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));  // faces +z
  }

  RigBuilder builder;
  std::vector<double> joints{0.0};
  for (int j = 0; j <= kHingeBones; ++j) joints.push_back(kStart + j * hinge_bone);
  const Chain chain = add_chain(builder, "cloth_", -1, Eigen::Affine3d::Identity(), joints, kWidth);
  for (std::size_t v = 0; v < vertex_x.size(); ++v) {
    for (const auto& [b, w] : chain_weights(chain, vertex_x[v], kBlend)) {
      builder.weight(static_cast<std::int32_t>(v), chain.nodes[static_cast<std::size_t>(b)], w);
    }
  }
  std::vector<std::int32_t> moving(chain.nodes.begin() + 1, chain.nodes.end());
  const std::vector<Eigen::Vector3d> axes(moving.size(), -Eigen::Vector3d::UnitY());
  Clip clip = rotation_clip("fold", builder, moving, axes, frames, [&](std::size_t, double tau) { return turn_end * tau; });

  GeneratedRig g;
  g.rig = builder.finish(std::move(mesh), "cloth", std::move(clip), "gen:cloth");

  // Known answer: the left part (x <= 1 − h at rest) never moves and lies in z = 0 exactly; the
  // right part (x >= end_joint + h) is flat and rigid. Margin: the largest −z of a right-part
  // vertex above the left part's rigid region. A vertex strictly below z = 0 there, with the rest
  // of the right part above it, means the two parts cross.
  const double h = 0.5 * kBlend * hinge_bone;
  const double left_end = kStart - h;
  g.answer.rule = "margin = max(-z) over the folded right part's vertices above the fixed left part (x in [0, 1 - h]); intersecting iff > 0";
  std::vector<Eigen::Index> right;
  for (std::size_t v = 0; v < vertex_x.size(); ++v) {
    if (vertex_x[v] >= end_joint + h) right.push_back(static_cast<Eigen::Index>(v));
  }
  posed_frames(g.rig, frames, [&](int, const Positions& p) {
    double margin = -std::numeric_limits<double>::infinity();
    for (const Eigen::Index v : right) {
      // Outside the left part's x range a vertex is as far as it is from that range.
      const double outside = std::max(0.0 - p(v, 0), p(v, 0) - left_end);
      margin = std::max(margin, outside > 0 ? -std::max(outside, std::abs(p(v, 2))) : -p(v, 2));
    }
    g.answer.margin.push_back(margin);
  });
  decide(g.answer, 1e-9);
  return g;
}

}  // namespace skelcd::skinning::generators
