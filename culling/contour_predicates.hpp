#pragma once
// Sign predicates of the cone methods' contour tests, in the projection along a direction V.
//
// Everything here is floating point with a derived rounding-error bound (docs/dual-cone.md,
// "Predicates"): a sign is returned only when proven; otherwise the answer is `uncertain`, and the
// callers treat uncertain as "the contour may intersect" — the safe side (no cull). No exact
// fallback is needed: declining a cull costs time, never a collision.
//
// The projection along V is never computed. Two projected points, segments or directions are
// compared through the two bilinear forms
//   det_V(a, b) = V · (a × b)                      (2D cross product of the projections, × |V|)
//   dot_V(a, b) = (a · b)(V · V) − (a · V)(b · V)  (2D dot product of the projections, × |V|²)
// which depend only on the components of a and b orthogonal to V, so the tests are exact
// statements about the projection along the stored double vector V.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>

namespace skelcd::culling {

/// Unit roundoff of double (2^-53).
inline constexpr double kUnitRoundoff = 0x1p-53;

enum class ProvenSign : std::int8_t { negative = -1, uncertain = 0, positive = 1 };

/// A computed value and a bound on its distance from the exact value it approximates.
struct BoundedValue {
  double value = 0.0;
  double error = 0.0;
};

[[nodiscard]] inline ProvenSign sign_of(const BoundedValue& x) {
  if (x.value > x.error) return ProvenSign::positive;
  if (x.value < -x.error) return ProvenSign::negative;
  return ProvenSign::uncertain;
}

/// det_V(a, b) = V · (a × b) where a and b are each the rounded difference of two doubles (or
/// exact), V exact. Error bound 8u·permanent: every one of the six products carries at most
/// seven roundings (two differences, the product, the pairwise subtraction, the product with V,
/// the three-term sum), γ7 < 8u including the rounding of the permanent itself.
[[nodiscard]] inline BoundedValue det_v(
    const Eigen::Vector3d& v, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double cx = a.y() * b.z() - a.z() * b.y();
  const double cy = a.z() * b.x() - a.x() * b.z();
  const double cz = a.x() * b.y() - a.y() * b.x();
  const double value = v.x() * cx + v.y() * cy + v.z() * cz;
  const double perm = std::abs(v.x()) * (std::abs(a.y() * b.z()) + std::abs(a.z() * b.y())) +
                      std::abs(v.y()) * (std::abs(a.z() * b.x()) + std::abs(a.x() * b.z())) +
                      std::abs(v.z()) * (std::abs(a.x() * b.y()) + std::abs(a.y() * b.x()));
  return {value, 8.0 * kUnitRoundoff * perm};
}

/// dot_V(a, b) = (a · b)(V · V) − (a · V)(b · V), a and b rounded differences, V exact. Each of
/// the eighteen degree-4 products carries at most twelve roundings (two differences, three in
/// a · b or a · V, three in V · V or b · V, the two products, the subtraction); bound 16u·M.
[[nodiscard]] inline BoundedValue dot_v(
    const Eigen::Vector3d& v, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double ab = a.dot(b);
  const double vv = v.dot(v);
  const double av = a.dot(v);
  const double bv = b.dot(v);
  const double value = ab * vv - av * bv;
  const Eigen::Vector3d aa = a.cwiseAbs();
  const Eigen::Vector3d ba = b.cwiseAbs();
  const Eigen::Vector3d va = v.cwiseAbs();
  const double m = aa.dot(ba) * vv + aa.dot(va) * ba.dot(va);
  return {value, 16.0 * kUnitRoundoff * m};
}

/// Sign over all of t in [0,1] of the quadratic with Bernstein coefficients c0, c1, c2 (each
/// within its error of the exact one): proven when all three clear their bounds with one sign
/// (convex-hull property), else after one de Casteljau split at t = 1/2 (errors carried).
[[nodiscard]] inline ProvenSign bernstein_quadratic_sign(
    const BoundedValue& c0, const BoundedValue& c1, const BoundedValue& c2) {
  const ProvenSign s0 = sign_of(c0);
  if (s0 == ProvenSign::uncertain) return s0;
  const ProvenSign s2 = sign_of(c2);
  if (s2 != s0) return ProvenSign::uncertain;
  const ProvenSign s1 = sign_of(c1);
  if (s1 == s0) return s0;
  // Split: left (c0, (c0+c1)/2, m), right (m, (c1+c2)/2, c2), m = (c0 + 2c1 + c2)/4. Each
  // halving and sum adds at most one rounding of its magnitude.
  const double u = kUnitRoundoff;
  const BoundedValue l1{
      0.5 * (c0.value + c1.value), 0.5 * (c0.error + c1.error) + u * std::abs(c0.value + c1.value)};
  const BoundedValue r1{
      0.5 * (c1.value + c2.value), 0.5 * (c1.error + c2.error) + u * std::abs(c1.value + c2.value)};
  const double mv = 0.5 * (l1.value + r1.value);
  const BoundedValue mid{mv, 0.5 * (l1.error + r1.error) + 2.0 * u * std::abs(mv)};
  if (sign_of(l1) == s0 && sign_of(r1) == s0 && sign_of(mid) == s0) return s0;
  return ProvenSign::uncertain;
}

/// Bernstein coefficients of F(A(t), B(t)) for a bilinear form F and linear A, B:
/// c0 = F(A0, B0), c1 = (F(A0, B1) + F(A1, B0)) / 2, c2 = F(A1, B1).
template <class Form>
[[nodiscard]] inline std::array<BoundedValue, 3> bernstein_bilinear(
    Form form,
    const Eigen::Vector3d& a0,
    const Eigen::Vector3d& a1,
    const Eigen::Vector3d& b0,
    const Eigen::Vector3d& b1) {
  const BoundedValue c0 = form(a0, b0);
  const BoundedValue c01 = form(a0, b1);
  const BoundedValue c10 = form(a1, b0);
  const BoundedValue c2 = form(a1, b1);
  const double s = 0.5 * (c01.value + c10.value);
  const BoundedValue c1{s, 0.5 * (c01.error + c10.error) + 2.0 * kUnitRoundoff * std::abs(s)};
  return {c0, c1, c2};
}

/// Two linear functionals x ↦ g1 · x, x ↦ g2 · x that vanish on V exactly (g = V × e_i for the
/// two coordinate axes e_i other than V's largest component; the components of g are components
/// of V, so g is exact and g · V = 0 exactly). They are coordinates of the projection along V
/// (not orthonormal: separation of boxes in them is still separation of the projections).
struct ProjectionFrame {
  Eigen::Vector3d g1;
  Eigen::Vector3d g2;
  int i = 0;  ///< the axis e_i of g1 (g1 = V × e_i)
  int j = 1;  ///< the axis e_j of g2
  int k = 2;  ///< V's largest component

  explicit ProjectionFrame(const Eigen::Vector3d& v) {
    k = 0;
    if (std::abs(v.y()) > std::abs(v(k))) k = 1;
    if (std::abs(v.z()) > std::abs(v(k))) k = 2;
    i = (k + 1) % 3;
    j = (k + 2) % 3;
    g1 = cross_axis(v, i);
    g2 = cross_axis(v, j);
  }

  /// Coordinate of point x on g, and a bound on its rounding error (two products and a sum of
  /// exact components: 2u; the caller's ± adds one more rounding: 4u with slack).
  [[nodiscard]] static BoundedValue coordinate(const Eigen::Vector3d& g, const Eigen::Vector3d& x) {
    const double value = g.dot(x);
    const double m = std::abs(g.x() * x.x()) + std::abs(g.y() * x.y()) + std::abs(g.z() * x.z());
    return {value, 4.0 * kUnitRoundoff * m};
  }

 private:
  static Eigen::Vector3d cross_axis(const Eigen::Vector3d& v, int axis) {
    switch (axis) {
      case 0:
        return {0.0, v.z(), -v.y()};
      case 1:
        return {-v.z(), 0.0, v.x()};
      default:
        return {v.y(), -v.x(), 0.0};
    }
  }
};

}  // namespace skelcd::culling
