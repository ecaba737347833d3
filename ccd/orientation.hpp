#pragma once
// Exact orientation of four points: Shewchuk's static floating-point filter first (inline, decides
// almost every call), then orient3d_exact: on exactly representable coordinate differences a
// zero row (four points in one axis plane) answers 0 at once, otherwise a filtered double with a
// proven dynamic error bound, floating-point expansions, and GMP rationals near underflow
// (ccd/detail/filtered.hpp, docs/ccd.md "Exact predicates").

#include <Eigen/Core>
#include <cmath>
#include <limits>

namespace skelcd::ccd {

/// The exact predicate behind orient3d (axis plane, filtered double, expansion, GMP): use
/// orient3d, which screens with a cheaper filter first.
[[nodiscard]] int orient3d_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d);

namespace detail {

/// Value returned by the static filters below when they cannot decide.
inline constexpr int kUndecided = 2;

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
  constexpr double kHalfUlp = std::numeric_limits<double>::epsilon() / 2.0;
  constexpr double kErrBound = (7.0 + 56.0 * kHalfUlp) * kHalfUlp;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  // The bound assumes no underflow (and finite values): otherwise leave it to the exact path.
  if (!(permanent > std::numeric_limits<double>::min() * 0x1p64) ||
      !(permanent < std::numeric_limits<double>::infinity())) {
    return kUndecided;
  }
  constexpr double kEta = std::numeric_limits<double>::denorm_min();
  const double bound = kErrBound * permanent +
                       2.0 * kEta * (std::abs(adz) + std::abs(bdz) + std::abs(cdz)) + 4.0 * kEta;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return kUndecided;
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
