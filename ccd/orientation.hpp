#pragma once
// Exact orientation of four points: Shewchuk's static floating-point filter first (inline, decides
// almost every call), then a filtered double with a proven dynamic error bound and a GMP rational
// fallback when neither can decide (ccd/detail/filtered.hpp, docs/ccd.md).

#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace skelcd::ccd {

/// The exact predicate behind orient3d (filtered double, then GMP): use orient3d, which screens
/// with a cheaper filter first.
[[nodiscard]] int orient3d_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d);

namespace detail {

/// Value returned by the static filters below when they cannot decide.
inline constexpr int kUndecided = 2;

/// The verdict of det3_sign_static from what it computes first: the 2 × 2 minors of the x and y
/// columns, c[k] (the difference of two products as rounded) and p[k] (the sum of their
/// magnitudes), and the z column (z0, z1, z2). Since det[a; b; z] = det of the transposed rows,
/// det3_sign_static(a_x, b_x, z_x, a_y, b_y, z_y, a_z, b_z, z_z) is this function of c = a × b:
/// a vertex fan's sectors against its normal (culling/vertex_fans.cpp) take their signs so, from
/// the products of their cross products, 1.3–1.5× faster there than det3_sign_static on the rows
/// (a, b, z).
[[gnu::always_inline]] inline int det3_sign_static_minors(
    double c0,
    double c1,
    double c2,
    double p0,
    double p1,
    double p2,
    double z0,
    double z1,
    double z2) {
  constexpr double kHalfUlp = std::numeric_limits<double>::epsilon() / 2.0;
  constexpr double kErrBound = (7.0 + 56.0 * kHalfUlp) * kHalfUlp;
  const double det = z0 * c0 + z1 * c1 + z2 * c2;
  const double permanent = p0 * std::abs(z0) + p1 * std::abs(z1) + p2 * std::abs(z2);
  // The bound assumes no underflow (and finite values): otherwise leave it to the exact path.
  if (!(permanent > std::numeric_limits<double>::min() * 0x1p64) ||
      !(permanent < std::numeric_limits<double>::infinity())) {
    return kUndecided;
  }
  constexpr double kEta = std::numeric_limits<double>::denorm_min();
  const double bound = kErrBound * permanent +
                       2.0 * kEta * (std::abs(z0) + std::abs(z1) + std::abs(z2)) + 4.0 * kEta;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return kUndecided;
}

/// Shewchuk's static orient3d filter ("Adaptive precision floating-point arithmetic and fast
/// robust geometric predicates", 1997) on differences already taken: D = det[a; b; c] (rows
/// a = (adx, ady, adz), …), each component rounded from at most one subtraction of exact inputs
/// (or exact itself), evaluated in double, is within (7 + 56ε) ε · permanent of the exact value
/// (ε = 2⁻⁵³) when no product underflows. A product that underflows is off by up to η/2
/// (η = 2⁻¹⁰⁷⁴, the smallest subnormal) more, and a 2 × 2 minor's error is then multiplied by a
/// coordinate difference that may be huge (2⁻⁵⁴⁰ · 2⁴⁹⁵ mixed in one query): the bound adds
/// 2η · (|adz| + |bdz| + |cdz|) + 4η, which covers the six minors' products (η each after the
/// minor's subtraction, grown by the outer product's rounding) and the three outer products (η/2
/// each); sums and differences of subnormals are exact. Returns the sign of D when |D| exceeds the
/// bound, kUndecided otherwise (also when the permanent is too small to rule out underflow, or not
/// finite).
inline int det3_sign_static(
    double adx,
    double ady,
    double adz,
    double bdx,
    double bdy,
    double bdz,
    double cdx,
    double cdy,
    double cdz) {
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  return det3_sign_static_minors(
      bdxcdy - cdxbdy,
      cdxady - adxcdy,
      adxbdy - bdxady,
      std::abs(bdxcdy) + std::abs(cdxbdy),
      std::abs(cdxady) + std::abs(adxcdy),
      std::abs(adxbdy) + std::abs(bdxady),
      adz,
      bdz,
      cdz);
}

/// Shewchuk's static orient3d filter on the points: det3_sign_static of D = det[a − d; b − d;
/// c − d]. Returns the sign of −D = (d − a) · ((b − a) × (c − a)) when it is certain, kUndecided
/// otherwise.
inline int orient3d_static(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  const int s = det3_sign_static(
      a.x() - d.x(),
      a.y() - d.y(),
      a.z() - d.z(),
      b.x() - d.x(),
      b.y() - d.y(),
      b.z() - d.z(),
      c.x() - d.x(),
      c.y() - d.y(),
      c.z() - d.z());
  return s == kUndecided ? s : -s;
}

/// Shewchuk's static orient2d filter on differences already taken: the sign of bx·cy − by·cx,
/// where (bx, by) = b − a and (cx, cy) = c − a were each rounded from one subtraction, when it
/// exceeds (3 + 16ε) ε · permanent (a bound that covers the differences' rounding), kUndecided
/// otherwise (as orient3d_static). Callers that need many signs from the same differences (a
/// vertex fan, culling/vertex_fans.cpp) take each difference once.
inline int cross_sign_static(double bx, double by, double cx, double cy) {
  constexpr double kHalfUlp = std::numeric_limits<double>::epsilon() / 2.0;
  constexpr double kErrBound = (3.0 + 16.0 * kHalfUlp) * kHalfUlp;
  const double left = bx * cy;
  const double right = by * cx;
  const double det = left - right;
  const double permanent = std::abs(left) + std::abs(right);
  if (!(permanent > std::numeric_limits<double>::min() * 0x1p64) ||
      !(permanent < std::numeric_limits<double>::infinity())) {
    return kUndecided;
  }
  const double bound = kErrBound * permanent;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return kUndecided;
}

/// Shewchuk's static orient2d filter applied to coordinates (i, j) of (b − a) × (c − a): the sign
/// of (b − a)_i (c − a)_j − (b − a)_j (c − a)_i when it exceeds (3 + 16ε) ε · permanent,
/// kUndecided otherwise (as orient3d_static).
inline int cross_component_static(
    const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, int i, int j) {
  return cross_sign_static(b[i] - a[i], b[j] - a[j], c[i] - a[i], c[j] - a[j]);
}

}  // namespace detail

/// Sign of det(b - a, c - a, d - a): +1 when d is on the side of the plane (a, b, c) its normal
/// (b - a) x (c - a) points to, -1 on the other side, 0 when the four points are coplanar (or a, b,
/// c are collinear). Exact for every finite input.
[[nodiscard]] inline int orient3d(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  const int s = detail::orient3d_static(a, b, c, d);
  return s != detail::kUndecided ? s : orient3d_exact(a, b, c, d);
}

}  // namespace skelcd::ccd
