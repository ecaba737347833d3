#include "culling/cones.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>

#include "culling/contour_predicates.hpp"

namespace skelcd::culling {
namespace {

constexpr double kU = kUnitRoundoff;
/// Absolute slack of one cone-combination step: the computed cos β and sin β of two unit axes
/// are within 9u and 11u of the exact values, the products and the sum add 3u (23u in all,
/// docs/dual-cone.md "Cones"); 32u is used.
constexpr double kStepSlack = 32.0 * kU;
/// A leaf cone wider than this (sin θ) is declared full: its triangle is nearly degenerate.
constexpr double kMaxLeafSin = 0.5;

/// Widens (cos_lb, sin_ub) — the bounds of a cone around unit `axis` — so that it also contains
/// cone c. Returns false when the result may reach π/2 (full).
bool extend_around(
    const Eigen::Vector3d& axis, const DirectionCone& c, double& cos_lb, double& sin_ub) {
  if (c.is_empty()) return true;
  if (c.is_full()) return false;
  // β = ∠(axis, c.axis); the cone c is inside the cone of half-angle θ_c + β around axis.
  const double cb = axis.dot(c.axis);
  if (!(cb > 0.0)) return false;  // β ≥ π/2 (or NaN)
  const double sb = axis.cross(c.axis).norm();
  // cos(θ + β) = cos θ cos β − sin θ sin β ≥ cos_lb·cb − sin_ub·sb (cb ≥ 0);
  // sin(θ + β) = sin θ cos β + cos θ sin β ≤ sin_ub·cb + sb.
  const double cs = c.cos_angle * cb - c.sin_angle * sb - kStepSlack;
  if (!(cs > 0.0)) return false;
  const double ss = std::min(1.0, c.sin_angle * cb + sb + kStepSlack);
  cos_lb = std::min(cos_lb, cs);
  sin_ub = std::max(sin_ub, ss);
  return true;
}

/// A bounded cone around unit `axis` from the running bounds, or full.
DirectionCone make_cone(const Eigen::Vector3d& axis, double cos_lb, double sin_ub) {
  DirectionCone r;
  r.kind = DirectionCone::Kind::bounded;
  r.axis = axis;
  r.cos_angle = cos_lb;
  r.sin_angle = sin_ub;
  return r;
}

}  // namespace

double DirectionCone::angle() const {
  if (kind == Kind::empty) return 0.0;
  if (kind == Kind::full) return 0.5 * std::numbers::pi;
  return std::min(std::acos(std::clamp(cos_angle, -1.0, 1.0)), std::asin(std::min(1.0, sin_angle)));
}

bool DirectionCone::contains(const Eigen::Vector3d& x) const {
  if (kind == Kind::full) return true;
  if (kind == Kind::empty) return false;
  const double n = x.norm();
  return x.dot(axis) >= n * cos_angle - 16.0 * kU * n;
}

Eigen::Vector3d unit_or_zero(const Eigen::Vector3d& v) {
  const double n = v.norm();
  if (!(n > 0.0) || !std::isfinite(n)) return Eigen::Vector3d::Zero();
  return v / n;
}

DirectionCone cone_of_vector(const Eigen::Vector3d& v, double error) {
  const double n = v.norm();
  if (!(n > 0.0) || !std::isfinite(n) || !std::isfinite(error)) return DirectionCone::full_cone();
  // The exact vector is within `error` of v: its angle to v is at most asin(error / |v|); the
  // computed norm (1.5u) and quotient (u) are covered by the (1 + 4u) factor, and the rounding
  // of the axis v / |v| (u per component) by the added 4u.
  const double s = error / n * (1.0 + 4.0 * kU) + 4.0 * kU;
  if (!(s <= kMaxLeafSin)) return DirectionCone::full_cone();
  return make_cone(v / n, std::sqrt(1.0 - s * s) - 4.0 * kU, s);
}

DirectionCone enclose_around(
    const Eigen::Vector3d& axis, const DirectionCone& a, const DirectionCone& b) {
  if (a.is_empty() && b.is_empty()) return DirectionCone::empty_cone();
  if (a.is_full() || b.is_full()) return DirectionCone::full_cone();
  if (axis.isZero(0.0)) return DirectionCone::full_cone();
  double cos_lb = 1.0;
  double sin_ub = 0.0;
  if (!extend_around(axis, a, cos_lb, sin_ub) || !extend_around(axis, b, cos_lb, sin_ub)) {
    return DirectionCone::full_cone();
  }
  return make_cone(axis, cos_lb, sin_ub);
}

DirectionCone merge(const DirectionCone& a, const DirectionCone& b) {
  if (a.is_empty()) return b;
  if (b.is_empty()) return a;
  if (a.is_full() || b.is_full()) return DirectionCone::full_cone();
  // Approximate angles choose the axis only; enclose_around makes the result conservative.
  const double ca = a.axis.dot(b.axis);
  const double sa = a.axis.cross(b.axis).norm();
  const double alpha = std::atan2(sa, ca);
  const double theta_a = std::atan2(a.sin_angle, a.cos_angle);
  const double theta_b = std::atan2(b.sin_angle, b.cos_angle);
  Eigen::Vector3d axis;
  if (alpha + theta_b <= theta_a) {
    axis = a.axis;
  } else if (alpha + theta_a <= theta_b) {
    axis = b.axis;
  } else {
    if (0.5 * (alpha + theta_a + theta_b) >= 0.5 * std::numbers::pi) {
      return DirectionCone::full_cone();
    }
    // Rotate a's axis towards b's by r: the minimal enclosing cone's axis.
    const double r = 0.5 * (alpha + theta_b - theta_a);
    axis = unit_or_zero(a.axis * std::sin(alpha - r) + b.axis * std::sin(r));
  }
  return enclose_around(axis, a, b);
}

BoundedNormal triangle_normal(
    const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d d1 = b - a;
  const Eigen::Vector3d d2 = c - a;
  // Per component: two rounded differences in each product (2u), the product (u), the
  // subtraction (u): 4u of the permanent; 6u covers the rounding of the bound and of the sum over
  // components (the Euclidean error is at most the sum of the component errors).
  const double perm = std::abs(d1.y() * d2.z()) + std::abs(d1.z() * d2.y()) +
                      std::abs(d1.z() * d2.x()) + std::abs(d1.x() * d2.z()) +
                      std::abs(d1.x() * d2.y()) + std::abs(d1.y() * d2.x());
  return {d1.cross(d2), 6.0 * kU * perm};
}

std::array<BoundedNormal, 3> continuous_normal_control_vectors(
    const Eigen::Vector3d& a_t0,
    const Eigen::Vector3d& b_t0,
    const Eigen::Vector3d& c_t0,
    const Eigen::Vector3d& a_t1,
    const Eigen::Vector3d& b_t1,
    const Eigen::Vector3d& c_t1) {
  // n(t) = e1(t) × e2(t) with e1, e2 linear: the product of two degree-1 Bernstein forms.
  const Eigen::Vector3d e1_0 = b_t0 - a_t0;
  const Eigen::Vector3d e2_0 = c_t0 - a_t0;
  const Eigen::Vector3d e1_1 = b_t1 - a_t1;
  const Eigen::Vector3d e2_1 = c_t1 - a_t1;
  auto perm = [](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return std::abs(p.y() * q.z()) + std::abs(p.z() * q.y()) + std::abs(p.z() * q.x()) +
           std::abs(p.x() * q.z()) + std::abs(p.x() * q.y()) + std::abs(p.y() * q.x());
  };
  const Eigen::Vector3d m01 = e1_0.cross(e2_1);
  const Eigen::Vector3d m10 = e1_1.cross(e2_0);
  const Eigen::Vector3d b1 = 0.5 * (m01 + m10);
  return {{
      {e1_0.cross(e2_0), 6.0 * kU * perm(e1_0, e2_0)},
      {b1, 3.0 * kU * (perm(e1_0, e2_1) + perm(e1_1, e2_0)) + 2.0 * kU * b1.cwiseAbs().sum()},
      {e1_1.cross(e2_1), 6.0 * kU * perm(e1_1, e2_1)},
  }};
}

DirectionCone boundary_binormal_cone(
    const std::array<Eigen::Vector3d, 3>& p_t0,
    const std::array<Eigen::Vector3d, 3>& p_t1,
    std::uint8_t sides,
    bool continuous) {
  DirectionCone bnc = DirectionCone::empty_cone();
  if (sides == 0) return bnc;
  const auto n =
      continuous_normal_control_vectors(p_t0[0], p_t0[1], p_t0[2], p_t1[0], p_t1[1], p_t1[2]);
  for (std::size_t k = 0; k < 3; ++k) {
    if ((sides & (1u << k)) == 0) continue;
    const Eigen::Vector3d e0 = p_t0[(k + 1) % 3] - p_t0[k];
    if (!continuous) {
      bnc = merge(bnc, cone_of_vector(n[0].n.cross(e0), 0.0));
      continue;
    }
    // n(t) (degree 2) × e(t) (degree 1): the degree-3 Bernstein product's control vectors.
    const Eigen::Vector3d e1 = p_t1[(k + 1) % 3] - p_t1[k];
    const Eigen::Vector3d c0 = n[0].n.cross(e0);
    const Eigen::Vector3d c1 = (2.0 * n[1].n.cross(e0) + n[0].n.cross(e1)) / 3.0;
    const Eigen::Vector3d c2 = (n[2].n.cross(e0) + 2.0 * n[1].n.cross(e1)) / 3.0;
    const Eigen::Vector3d c3 = n[2].n.cross(e1);
    for (const auto& c : {c0, c1, c2, c3}) bnc = merge(bnc, cone_of_vector(c, 0.0));
  }
  return bnc;
}

void NormalConeTree::refit(
    const AabbBvh& bvh, const FeatureTopology& topology, const skinning::Positions& x) {
  topology_ = &topology;
  x_t0_ = &x;
  x_t1_ = nullptr;
  vectors_per_triangle_ = 1;
  refit_nodes(bvh);
}

void NormalConeTree::refit(
    const AabbBvh& bvh,
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  topology_ = &topology;
  x_t0_ = &x_t0;
  x_t1_ = &x_t1;
  vectors_per_triangle_ = 3;
  refit_nodes(bvh);
}

std::array<BoundedNormal, 3> NormalConeTree::triangle_normals(std::int32_t f) const {
  const auto& t = topology_->triangle(f);
  const skinning::Positions& x0 = *x_t0_;
  if (x_t1_ == nullptr) {
    return {triangle_normal(
        x0.row(t[0]).transpose(), x0.row(t[1]).transpose(), x0.row(t[2]).transpose())};
  }
  const skinning::Positions& x1 = *x_t1_;
  return continuous_normal_control_vectors(
      x0.row(t[0]).transpose(),
      x0.row(t[1]).transpose(),
      x0.row(t[2]).transpose(),
      x1.row(t[0]).transpose(),
      x1.row(t[1]).transpose(),
      x1.row(t[2]).transpose());
}

DirectionCone NormalConeTree::triangle_cone(const std::array<BoundedNormal, 3>& b) const {
  if (vectors_per_triangle_ == 1) return cone_of_vector(b[0].n, b[0].error);
  // The cone of the three control vectors (each within its error ball) around their mean
  // direction; with θ < π/2 it is convex and so contains n(t) for every t in [0,1].
  const DirectionCone c0 = cone_of_vector(b[0].n, b[0].error);
  const DirectionCone c1 = cone_of_vector(b[1].n, b[1].error);
  const DirectionCone c2 = cone_of_vector(b[2].n, b[2].error);
  if (c0.is_full() || c1.is_full() || c2.is_full()) return DirectionCone::full_cone();
  const Eigen::Vector3d axis = unit_or_zero(c0.axis + c1.axis + c2.axis);
  double cos_lb = 1.0;
  double sin_ub = 0.0;
  if (!axis.isZero(0.0) && extend_around(axis, c0, cos_lb, sin_ub) &&
      extend_around(axis, c1, cos_lb, sin_ub) && extend_around(axis, c2, cos_lb, sin_ub)) {
    return make_cone(axis, cos_lb, sin_ub);
  }
  return DirectionCone::full_cone();
}

Eigen::Vector3d NormalConeTree::triangle_sum(const std::array<BoundedNormal, 3>& b) const {
  if (vectors_per_triangle_ == 1) return b[0].n;
  return b[0].n + b[1].n + b[2].n;
}

void NormalConeTree::leaf_cone(
    const AabbBvh& bvh, std::int32_t leaf, DirectionCone& cone, Eigen::Vector3d& sum) const {
  const BvhNode& node = bvh.nodes()[static_cast<std::size_t>(leaf)];
  const auto order = bvh.triangle_order();
  if (node.size() == 1) {
    const auto normals = triangle_normals(order[static_cast<std::size_t>(node.begin)]);
    sum = Eigen::Vector3d::Zero();
    sum += triangle_sum(normals);
    cone = triangle_cone(normals);
    return;
  }
  sum = Eigen::Vector3d::Zero();
  for (std::int32_t s = node.begin; s < node.end; ++s) {
    sum += triangle_sum(triangle_normals(order[static_cast<std::size_t>(s)]));
  }
  const Eigen::Vector3d axis = unit_or_zero(sum);
  double cos_lb = 1.0;
  double sin_ub = 0.0;
  bool bounded = !axis.isZero(0.0);
  for (std::int32_t s = node.begin; bounded && s < node.end; ++s) {
    bounded = extend_around(
        axis, triangle_cone(triangle_normals(order[static_cast<std::size_t>(s)])), cos_lb, sin_ub);
  }
  cone = bounded ? make_cone(axis, cos_lb, sin_ub) : DirectionCone::full_cone();
}

void NormalConeTree::combine(
    const std::array<DirectionCone, 2>& cones,
    const std::array<Eigen::Vector3d, 2>& sums,
    DirectionCone& cone,
    Eigen::Vector3d& sum) {
  sum = sums[0] + sums[1];
  // Axis: the node's mean normal (cheap); when that leaves a wide cone, the optimal merge axis
  // of the two children may do better (it costs a few transcendental calls).
  cone = enclose_around(unit_or_zero(sum), cones[0], cones[1]);
  if (cone.is_full() || cone.cos_angle < 0.5) {
    const DirectionCone alt = merge(cones[0], cones[1]);
    if (!alt.is_full() && (cone.is_full() || alt.cos_angle > cone.cos_angle)) cone = alt;
  }
}

void NormalConeTree::unstored_cone(
    const AabbBvh& bvh, std::int32_t node, DirectionCone& cone, Eigen::Vector3d& sum) const {
  const BvhNode& n = bvh.nodes()[static_cast<std::size_t>(node)];
  if (n.is_leaf()) {
    leaf_cone(bvh, node, cone, sum);
    return;
  }
  // Both children are leaves: merged as the refit merges any two children.
  std::array<DirectionCone, 2> cones;
  std::array<Eigen::Vector3d, 2> sums;
  leaf_cone(bvh, node + 1, cones[0], sums[0]);
  leaf_cone(bvh, n.right, cones[1], sums[1]);
  combine(cones, sums, cone, sum);
}

DirectionCone NormalConeTree::node_cone(const AabbBvh& bvh, std::int32_t node) const {
  const std::int32_t k = internal_index_[static_cast<std::size_t>(node)];
  if (k >= 0) return node_cones_[static_cast<std::size_t>(k)];
  DirectionCone cone;
  Eigen::Vector3d sum;
  unstored_cone(bvh, node, cone, sum);
  return cone;
}

Eigen::Vector3d NormalConeTree::mean_normal(const AabbBvh& bvh, std::int32_t node) const {
  const std::int32_t k = internal_index_[static_cast<std::size_t>(node)];
  if (k >= 0) return unit_or_zero(node_sums_[static_cast<std::size_t>(k)]);
  DirectionCone cone;
  Eigen::Vector3d sum;
  unstored_cone(bvh, node, cone, sum);
  return unit_or_zero(sum);
}

bool NormalConeTree::normals_in_half_space(
    const AabbBvh& bvh, std::int32_t node, const Eigen::Vector3d& v) const {
  if (!std::isfinite(v.squaredNorm()) || v.isZero(0.0)) return false;
  const BvhNode& n = bvh.nodes()[static_cast<std::size_t>(node)];
  const auto order = bvh.triangle_order();
  const double vn = v.norm() * (1.0 + 4.0 * kU);
  for (std::int32_t s = n.begin; s < n.end; ++s) {
    const auto normals = triangle_normals(order[static_cast<std::size_t>(s)]);
    for (int k = 0; k < vectors_per_triangle_; ++k) {
      // The exact normal is within `error` of the computed one: n·v ≥ ñ·v − error·|v|; the dot
      // product itself is within 3u·Σ|ñ_i v_i| (4u with the bound's own rounding).
      const BoundedNormal& b = normals[static_cast<std::size_t>(k)];
      const double d = b.n.dot(v);
      const double m =
          std::abs(b.n.x() * v.x()) + std::abs(b.n.y() * v.y()) + std::abs(b.n.z() * v.z());
      if (!(d > b.error * vn + 4.0 * kU * m)) return false;
    }
  }
  return true;
}

void NormalConeTree::refit_nodes(const AabbBvh& bvh) {
  const auto nodes = bvh.nodes();
  // Records for the internal nodes with an internal child only, numbered in node order: a leaf's
  // cone and sum, and those of a node whose children are both leaves (which no cone method
  // tests), are formed from their one to a few triangles when needed (a pass over the node ids;
  // allocation-free once sized).
  const auto stored = [&](std::size_t i) {
    return !nodes[i].is_leaf() &&
           !(nodes[i + 1].is_leaf() && nodes[static_cast<std::size_t>(nodes[i].right)].is_leaf());
  };
  internal_index_.resize(nodes.size());
  std::int32_t records = 0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    internal_index_[i] = stored(i) ? records++ : -1;
  }
  node_cones_.resize(static_cast<std::size_t>(records));
  node_sums_.resize(static_cast<std::size_t>(records));
  // Depth-first layout: children have larger ids than their parent, so one backward sweep is
  // bottom-up.
  for (std::size_t i = nodes.size(); i-- > 0;) {
    const std::int32_t k = internal_index_[i];
    if (k < 0) continue;
    // The children's cones and sums: a stored child's record, or formed from its triangles
    // (each node has one parent: formed once per refit, from the triangles as before).
    std::array<DirectionCone, 2> cones;
    std::array<Eigen::Vector3d, 2> sums;
    for (std::size_t side = 0; side < 2; ++side) {
      const std::size_t c = side == 0 ? i + 1 : static_cast<std::size_t>(nodes[i].right);
      const std::int32_t kc = internal_index_[c];
      if (kc >= 0) {
        cones[side] = node_cones_[static_cast<std::size_t>(kc)];
        sums[side] = node_sums_[static_cast<std::size_t>(kc)];
      } else {
        unstored_cone(bvh, static_cast<std::int32_t>(c), cones[side], sums[side]);
      }
    }
    combine(
        cones,
        sums,
        node_cones_[static_cast<std::size_t>(k)],
        node_sums_[static_cast<std::size_t>(k)]);
  }
}

}  // namespace skelcd::culling
