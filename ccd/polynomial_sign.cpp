// Sign of a cubic on [0,1] (docs/ccd.md, "Sign of a cubic on [0,1]"). A cubic lies inside the convex
// hull of its Bernstein coefficients over [0,1], so if every coefficient is provably positive the
// cubic is. Each conversion carries an absolute error bound from the rounding lemma of
// detail/float_bounds.hpp.

#include "ccd/polynomial_sign.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/lanes.hpp"
#include "ccd/detail/trilinear_cubic.hpp"

namespace skelcd::ccd {
namespace {

using detail::add_up;
using detail::kEps;
using detail::kRoundUp;
using detail::kUnderflowUnit;
using detail::Lanes;
using detail::Lanes3;
using detail::rounding_bound;

double max_abs(const std::array<double, 4>& c) {
  return std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2]), std::abs(c[3])});
}

// Certain sign of the hull of the coefficients, or uncertain.
PolynomialSign hull_sign(const std::array<double, 4>& b, double error) {
  // Written as "b > error" so that NaN (or an infinite error) falls through to uncertain.
  if (b[0] > error && b[1] > error && b[2] > error && b[3] > error) return PolynomialSign::positive;
  if (-b[0] > error && -b[1] > error && -b[2] > error && -b[3] > error) {
    return PolynomialSign::negative;
  }
  return PolynomialSign::uncertain;
}

PolynomialSign subdivided_sign(const std::array<double, 4>& b, double error, int depth) {
  const PolynomialSign s = hull_sign(b, error);
  if (s != PolynomialSign::uncertain || depth <= 0) return s;
  // A sign change among the end values is a root: no subdivision can help.
  if ((b[0] > error && -b[3] > error) || (-b[0] > error && b[3] > error)) {
    return PolynomialSign::uncertain;
  }
  // de Casteljau at t = 1/2. Every new coefficient is a convex combination of the old ones (the
  // old errors carry over unchanged) computed with at most 3 roundings of averages of values
  // bounded by M = max|b| + error: +fl(4 eps M) (rounding lemma, k = 3), plus underflow of the
  // halvings.
  const double b01 = (b[0] + b[1]) * 0.5;
  const double b12 = (b[1] + b[2]) * 0.5;
  const double b23 = (b[2] + b[3]) * 0.5;
  const double b012 = (b01 + b12) * 0.5;
  const double b123 = (b12 + b23) * 0.5;
  const double mid = (b012 + b123) * 0.5;
  const double m = add_up(max_abs(b), error);
  const double next_error = add_up(add_up(error, rounding_bound(3, m)), 3 * kUnderflowUnit);
  const PolynomialSign left = subdivided_sign({b[0], b01, b012, mid}, next_error, depth - 1);
  if (left == PolynomialSign::uncertain) return left;
  const PolynomialSign right = subdivided_sign({mid, b123, b23, b[3]}, next_error, depth - 1);
  return left == right ? left : PolynomialSign::uncertain;
}

}  // namespace

namespace detail {

// The blossom of the trilinear det: b_i averages the dets d_ijk = X_i . (Y_j x Z_k) with i + j + k
// factors taken at t = 1, and the permanents likewise (the coefficients: trilinear_cubic.hpp).
double trilinear_error(const DifferenceTriple& t0, const DifferenceTriple& t1) {
  const Lanes3 ay = lane_abs(lanes3(t0.y, t1.y));
  const Lanes3 p_z0 = cross_permanent(ay, lane_abs(lanes3(t0.z, t0.z)));
  const Lanes3 p_z1 = cross_permanent(ay, lane_abs(lanes3(t1.z, t1.z)));
  const Lanes3 ax0 = lane_abs(lanes3(t0.x, t0.x)), ax1 = lane_abs(lanes3(t1.x, t1.x));
  const Lanes p0x0 = dot(ax0, p_z0), p1x0 = dot(ax1, p_z0);
  const Lanes p0x1 = dot(ax0, p_z1), p1x1 = dot(ax1, p_z1);
  const Lanes mid_perm =
      ((Lanes{p1x0[0], p0x1[1]} + Lanes{p0x0[1], p1x1[0]}) + Lanes{p0x1[0], p1x0[1]}) / 3.0;
  const double perm = std::max({p0x0[0], mid_perm[0], mid_perm[1], p1x1[1]});
  // Rounding count per product term: difference 1 each for x, y, z; y*z 3; the cross-product
  // difference 4; x * (.) 6; the two sums of the dot 8; the two sums and the /3 of the average 11.
  const double relative = rounding_bound(11, perm);
  // Underflow: each of the 6 products y*z may lose kUnderflowUnit, then scaled by |x| <= mx; each
  // x*(.) product and the /3 may lose one more.
  const double mx = std::max(t0.x.cwiseAbs().maxCoeff(), t1.x.cwiseAbs().maxCoeff());
  // 16 kUnderflowUnit (1 + mx) = 2^-1070 (1 + mx), computed without a subnormal product.
  const double underflow = detail::times_subnormal_power_of_two<1070>(1.0 + mx);
  return add_up(relative, underflow);
}

BernsteinCubic trilinear_determinant(const DifferenceTriple& t0, const DifferenceTriple& t1) {
  return {trilinear_coefficients(t0, t1), trilinear_error(t0, t1)};
}

double cross_norm_bound(const DifferenceTriple& t0, const DifferenceTriple& t1) {
  // n(t) = Y(t) x Z(t) is quadratic per component with Bernstein coefficients N0 = Y0 x Z0,
  // N1 = (Y0 x Z1 + Y1 x Z0) / 2, N2 = Y1 x Z1; |n_k(t)| <= max_i |N_i,k| and |n| <= sum_k |n_k|.
  const auto cross_perm = [](const Eigen::Vector3d& y, const Eigen::Vector3d& z) {
    const Eigen::Vector3d ay = y.cwiseAbs();
    const Eigen::Vector3d az = z.cwiseAbs();
    return Eigen::Vector3d(ay[1] * az[2] + ay[2] * az[1], ay[2] * az[0] + ay[0] * az[2],
                           ay[0] * az[1] + ay[1] * az[0]);
  };
  const Eigen::Vector3d n0 = t0.y.cross(t0.z);
  const Eigen::Vector3d n1 = (t0.y.cross(t1.z) + t1.y.cross(t0.z)) * 0.5;
  const Eigen::Vector3d n2 = t1.y.cross(t1.z);
  const Eigen::Vector3d p0 = cross_perm(t0.y, t0.z);
  const Eigen::Vector3d p1 = (cross_perm(t0.y, t1.z) + cross_perm(t1.y, t0.z)) * 0.5;
  const Eigen::Vector3d p2 = cross_perm(t1.y, t1.z);
  double bound = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double m = std::max({std::abs(n0[k]), std::abs(n1[k]), std::abs(n2[k])});
    const double perm = std::max({p0[k], p1[k], p2[k]});
    // Rounding count: differences 1, products 3, the cross difference 4, the sum and halving 6.
    const double err = add_up(rounding_bound(6, perm), 4 * kUnderflowUnit);
    bound = add_up(bound, add_up(m, err));
  }
  return bound;
}

}  // namespace detail

BernsteinCubic to_bernstein(const PowerCubic& f) {
  const auto& c = f.coefficients;
  BernsteinCubic b;
  b.coefficients = {c[0], c[0] + c[1] / 3.0, c[0] + (2.0 * c[1] + c[2]) / 3.0, c[0] + c[1] + c[2] + c[3]};
  // Each b_i = sum_j w_ij c_j with 0 <= w_ij and sum_j w_ij <= 4: input errors grow by at most 4x;
  // at most 3 roundings per term (rounding lemma, k = 3) of a sum bounded by sum_j |c_j|.
  const double perm = std::abs(c[0]) + std::abs(c[1]) + std::abs(c[2]) + std::abs(c[3]);
  b.error = add_up(add_up(4.0 * f.error, rounding_bound(3, perm)), 2 * kUnderflowUnit);
  return b;
}

PowerCubic to_power(const BernsteinCubic& f) {
  const auto& b = f.coefficients;
  PowerCubic p;
  p.coefficients = {b[0], 3.0 * (b[1] - b[0]), 3.0 * ((b[0] - 2.0 * b[1]) + b[2]),
                    (b[3] - b[0]) + 3.0 * (b[1] - b[2])};
  // Weights sum (in absolute value) to at most 12 (c2 = 3 b0 - 6 b1 + 3 b2); 3 roundings per term.
  const double m = max_abs(b);
  p.error = add_up(12.0 * f.error, rounding_bound(3, 12.0 * m));
  return p;
}

BernsteinCubic bernstein_from_values(const std::array<double, 4>& v, double value_error) {
  // Interpolation at 0, 1/3, 2/3, 1 in the Bernstein basis.
  BernsteinCubic b;
  b.coefficients = {v[0], (-5.0 * v[0] + 18.0 * v[1] - 9.0 * v[2] + 2.0 * v[3]) / 6.0,
                    (2.0 * v[0] - 9.0 * v[1] + 18.0 * v[2] - 5.0 * v[3]) / 6.0, v[3]};
  // Absolute weights sum to 34/6 < 6; 5 roundings per term (constant product, 3 sums, /6).
  const double m = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2]), std::abs(v[3])});
  b.error = add_up(add_up(6.0 * value_error, rounding_bound(5, 6.0 * m)), 8 * kUnderflowUnit);
  return b;
}

PolynomialSign cubic_sign(const BernsteinCubic& f, int max_subdivisions) {
  for (const double b : f.coefficients) {
    if (!std::isfinite(b)) return PolynomialSign::uncertain;
  }
  if (!std::isfinite(f.error)) return PolynomialSign::uncertain;
  return subdivided_sign(f.coefficients, f.error, max_subdivisions);
}

PolynomialSign cubic_sign(const PowerCubic& f, int max_subdivisions) {
  return cubic_sign(to_bernstein(f), max_subdivisions);
}

namespace {
void orientation_differences(const MovingOrientationQuery& q,
                             detail::DifferenceTriple& t0,
                             detail::DifferenceTriple& t1) {
  t0 = {q.a_t0 - q.q_t0, q.b_t0 - q.a_t0, q.c_t0 - q.a_t0};
  t1 = {q.a_t1 - q.q_t1, q.b_t1 - q.a_t1, q.c_t1 - q.a_t1};
}
}  // namespace

BernsteinCubic moving_orientation_cubic(const MovingOrientationQuery& query) {
  detail::DifferenceTriple t0, t1;
  orientation_differences(query, t0, t1);
  return detail::trilinear_determinant(t0, t1);
}

PolynomialSign moving_orientation_sign(const MovingOrientationQuery& query, int max_subdivisions) {
  detail::DifferenceTriple t0, t1;
  orientation_differences(query, t0, t1);
  const detail::TrilinearScreen screen = detail::trilinear_screen(t0, t1);
  const auto& b = screen.coefficients;
  // cubic_sign's finiteness check, then its first test (hull_sign) with the larger error: NaN
  // fails every comparison, and error_upper is +inf or NaN whenever the exact bound is not finite.
  constexpr double kMax = std::numeric_limits<double>::max();
  if (std::abs(b[0]) <= kMax && std::abs(b[1]) <= kMax && std::abs(b[2]) <= kMax &&
      std::abs(b[3]) <= kMax) {
    const PolynomialSign s = hull_sign(b, screen.error_upper);
    if (s != PolynomialSign::uncertain) return s;
  }
  return cubic_sign(
      BernsteinCubic{screen.coefficients, detail::trilinear_error(t0, t1)}, max_subdivisions);
}

double moving_normal_bound(const MovingOrientationQuery& query) {
  detail::DifferenceTriple t0, t1;
  orientation_differences(query, t0, t1);
  return detail::cross_norm_bound(t0, t1);
}

}  // namespace skelcd::ccd
