// Tubes on bone chains: the rope (closed, coils onto itself) and the pipe (open, folds onto itself).
//
// Both tubes run along +x at rest with a regular M-gon cross-section (M a multiple of 4, rotated
// half a segment so that a flat facet faces each of +y, +z, −y, −z). The tube's first part is one
// long bone that never moves; the part after the last joint is rigid on the last bone. The known
// answer measures how deep the rigid end part's vertices reach into the rigid start part's prism
// (see end_depth_margin).

#include <algorithm>
#include <cmath>
#include <numbers>

#include "skinning/generators_common.hpp"

namespace skelcd::skinning::generators {
namespace {

constexpr double kPi = std::numbers::pi;

struct Tube {
  MeshBuilder mesh;
  std::vector<double> vertex_s;          ///< arc length of each vertex at rest
  std::vector<std::vector<std::int32_t>> rings;
};

// Rings k = 0 … K−1 at s = length · k / (K − 1), vertex m at angle (m + ½) · 2π/M from +y towards
// +z; optionally capped by fans around centre vertices on the axis.
Tube build_tube(double length, double radius, std::int64_t m_segments, std::int64_t k_rings, bool caps) {
  Tube t;
  const auto m = static_cast<std::int32_t>(m_segments);
  for (std::int64_t k = 0; k < k_rings; ++k) {
    const double s = length * static_cast<double>(k) / static_cast<double>(k_rings - 1);
    std::vector<std::int32_t> ring;
    for (std::int32_t j = 0; j < m; ++j) {
      const double phi = (j + 0.5) * 2.0 * kPi / m;
      ring.push_back(t.mesh.add({s, radius * std::cos(phi), radius * std::sin(phi)}));
      t.vertex_s.push_back(s);
    }
    t.rings.push_back(std::move(ring));
  }
  // Walls: the angle grows counter-clockwise seen from +x, so (a, d, c, b) faces outwards.
  for (std::size_t k = 0; k + 1 < t.rings.size(); ++k) {
    for (std::int32_t j = 0; j < m; ++j) {
      const std::int32_t j1 = (j + 1) % m;
      t.mesh.quad(t.rings[k][static_cast<std::size_t>(j)], t.rings[k][static_cast<std::size_t>(j1)],
                  t.rings[k + 1][static_cast<std::size_t>(j1)], t.rings[k + 1][static_cast<std::size_t>(j)]);
    }
  }
  if (caps) {
    const std::int32_t c0 = t.mesh.add({0, 0, 0});
    t.vertex_s.push_back(0);
    const std::int32_t c1 = t.mesh.add({length, 0, 0});
    t.vertex_s.push_back(length);
    const auto& first = t.rings.front();
    const auto& last = t.rings.back();
    for (std::int32_t j = 0; j < m; ++j) {
      const auto a = static_cast<std::size_t>(j);
      const auto b = static_cast<std::size_t>((j + 1) % m);
      t.mesh.tri(c0, first[b], first[a]);  // faces −x
      t.mesh.tri(c1, last[a], last[b]);    // faces +x
    }
  }
  return t;
}

// Signed depth of point p inside the prism {x in [x0, x1]} × (regular M-gon of circumradius r,
// facets centred at angles 2πm/M from +y): positive strictly inside, negative outside. The facet
// that bounds p is the one whose centre angle is nearest p's polar angle.
double prism_depth(const Eigen::Vector3d& p, double x0, double x1, double r, std::int64_t m_segments) {
  const auto m = static_cast<double>(m_segments);
  const double inner = r * std::cos(kPi / m);
  const double step = 2.0 * kPi / m;
  const double angle = std::atan2(p.z(), p.y());
  const double phi = step * std::round(angle / step);
  return std::min({p.x() - x0, x1 - p.x(), inner - (p.y() * std::cos(phi) + p.z() * std::sin(phi))});
}

// Known answer: per frame, the largest depth of the end part's vertices (arc length >= s_end)
// inside the start part's prism (x in [0, s_start], never moving). A vertex of the surface
// strictly inside the solid bounded by another part of it means the surface crosses itself;
// depth < 0 for every vertex is the frames before the end reaches the start part.
KnownAnswer end_depth_margin(
    const Rig& rig,
    const Tube& tube,
    int frames,
    double s_start,
    double s_end,
    double radius,
    std::int64_t m_segments,
    const std::string& rule) {
  KnownAnswer answer;
  answer.rule = rule;
  std::vector<Eigen::Index> end_vertices;
  for (std::size_t v = 0; v < tube.vertex_s.size(); ++v) {
    if (tube.vertex_s[v] >= s_end) end_vertices.push_back(static_cast<Eigen::Index>(v));
  }
  posed_frames(rig, frames, [&](int, const Positions& p) {
    double margin = -std::numeric_limits<double>::infinity();
    for (const Eigen::Index v : end_vertices) {
      margin = std::max(margin, prism_depth(p.row(v).transpose(), 0.0, s_start, radius, m_segments));
    }
    answer.margin.push_back(margin);
  });
  decide(answer, 1e-9);
  return answer;
}

// Segments around and rings along for about `triangles` triangles of roughly square shape.
std::pair<std::int64_t, std::int64_t> tube_resolution(std::int64_t triangles, double length, double radius, bool caps) {
  const double around = std::sqrt(static_cast<double>(triangles) * kPi * radius / length);
  const std::int64_t m = std::max<std::int64_t>(8, 4 * std::llround(around / 4));
  // Closed: 2·M·K triangles (walls 2M(K−1), caps 2M); open: 2·M·(K−1).
  const double per_ring = 2.0 * static_cast<double>(m);
  const std::int64_t k = caps ? round_at_least(static_cast<double>(triangles) / per_ring, 2)
                              : round_at_least(static_cast<double>(triangles) / per_ring, 1) + 1;
  return {m, k};
}

}  // namespace

// Rope: a closed tube 10 long, radius 0.15. Bone 0 covers s in [0, 3] and stays; 16 coil bones of
// 0.4 and an end bone of 0.6 follow, and each of the 17 joints turns about +z. The chain curls counter-clockwise into a loop whose end (heading down) comes back onto the start
// part from above near x = 2 and pushes into it (from about 17.7° per joint). Each joint turns by
// 19° · (1 − (1 − τ)²).
GeneratedRig generate_rope(std::int64_t triangles, int frames) {
  constexpr double kLength = 10.0;
  constexpr double kRadius = 0.15;
  constexpr double kStart = 3.0;
  constexpr double kCoilBone = 0.4;
  constexpr int kCoilBones = 16;
  constexpr double kEndJoint = kStart + kCoilBones * kCoilBone;  // 9.4
  constexpr double kBlend = 1.0;
  const double turn_end = 19.0 * kPi / 180.0;

  const auto [m, k] = tube_resolution(triangles, kLength, kRadius, true);
  Tube tube = build_tube(kLength, kRadius, m, k, true);

  RigBuilder builder;
  std::vector<double> joints{0.0};
  for (int j = 0; j <= kCoilBones; ++j) joints.push_back(kStart + j * kCoilBone);
  const Chain chain = add_chain(builder, "rope_", -1, Eigen::Affine3d::Identity(), joints, kLength);
  for (std::size_t v = 0; v < tube.vertex_s.size(); ++v) {
    for (const auto& [b, w] : chain_weights(chain, tube.vertex_s[v], kBlend)) {
      builder.weight(static_cast<std::int32_t>(v), chain.nodes[static_cast<std::size_t>(b)], w);
    }
  }
  std::vector<std::int32_t> moving(chain.nodes.begin() + 1, chain.nodes.end());
  const std::vector<Eigen::Vector3d> axes(moving.size(), Eigen::Vector3d::UnitZ());
  // Ease out: fast at first, slowing down as the end presses through the start part.
  Clip clip = rotation_clip("coil", builder, moving, axes, frames,
                            [&](std::size_t, double tau) { return turn_end * (1 - (1 - tau) * (1 - tau)); });

  GeneratedRig g;
  g.rig = builder.finish(std::move(tube.mesh), "rope", std::move(clip), "gen:rope");
  // Rigid parts: s <= 3 − 0.2 (bone 0 before the first blend zone) and s >= 9.4 + 0.2.
  const double h = 0.5 * kBlend * std::min(kCoilBone, kLength - kEndJoint);
  g.answer = end_depth_margin(g.rig, tube, frames, kStart - 0.5 * kBlend * kCoilBone, kEndJoint + h, kRadius, m,
                              "margin = depth of the rope's rigid end (s >= 9.6) inside the prism of its fixed start part (s <= 2.8); "
                              "intersecting iff > 0");
  return g;
}

// Pipe: an open tube 4 long, radius 0.1, lying along +x. Bone 0 covers s in [0, 2] and stays; a
// hinge of 6 bones of 0.1035 (joints turning about −y, so +x bends up) folds the last bone
// (s in [2.62, 4]) up, over and back onto the first half: at 180° the halves are parallel about
// 0.4 apart (axes), beyond it the folded end tilts down and its rim pushes into the first half
// near x = 0.6. Each hinge joint turns by 35° · τ.
GeneratedRig generate_pipe(std::int64_t triangles, int frames) {
  constexpr double kLength = 4.0;
  constexpr double kRadius = 0.1;
  constexpr double kStart = 2.0;
  constexpr int kHingeBones = 6;
  constexpr double kBlend = 1.0;
  const double hinge_bone = 0.4 * std::sin(15.0 * kPi / 180.0);  // hinge radius 0.2 at 30° per joint
  const double end_joint = kStart + kHingeBones * hinge_bone;
  const double turn_end = 35.0 * kPi / 180.0;

  const auto [m, k] = tube_resolution(triangles, kLength, kRadius, false);
  Tube tube = build_tube(kLength, kRadius, m, k, false);

  RigBuilder builder;
  std::vector<double> joints{0.0};
  for (int j = 0; j <= kHingeBones; ++j) joints.push_back(kStart + j * hinge_bone);
  const Chain chain = add_chain(builder, "pipe_", -1, Eigen::Affine3d::Identity(), joints, kLength);
  for (std::size_t v = 0; v < tube.vertex_s.size(); ++v) {
    for (const auto& [b, w] : chain_weights(chain, tube.vertex_s[v], kBlend)) {
      builder.weight(static_cast<std::int32_t>(v), chain.nodes[static_cast<std::size_t>(b)], w);
    }
  }
  std::vector<std::int32_t> moving(chain.nodes.begin() + 1, chain.nodes.end());
  const std::vector<Eigen::Vector3d> axes(moving.size(), -Eigen::Vector3d::UnitY());
  Clip clip = rotation_clip("fold", builder, moving, axes, frames, [&](std::size_t, double tau) { return turn_end * tau; });

  GeneratedRig g;
  g.rig = builder.finish(std::move(tube.mesh), "pipe", std::move(clip), "gen:pipe");
  const double h = 0.5 * kBlend * hinge_bone;
  g.answer = end_depth_margin(g.rig, tube, frames, kStart - h, end_joint + h, kRadius, m,
                              "margin = depth of the pipe's folded rigid end (after the hinge) inside the prism of its fixed first half; "
                              "intersecting iff > 0");
  return g;
}

}  // namespace skelcd::skinning::generators
