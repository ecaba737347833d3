#pragma once
// The cubic det(X(t), Y(t), Z(t)) of three linearly moving difference vectors, in Bernstein form with
// a rounding-error bound, and a bound on |Y(t) x Z(t)|. Shared by the public orientation cubic
// (polynomial_sign.hpp) and the CCD coplanarity filter (filters.cpp). Derivation: docs/ccd.md.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <limits>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/lanes.hpp"
#include "ccd/polynomial_sign.hpp"

namespace skelcd::ccd::detail {

/// Difference vectors at one end of the interval. Each coordinate must be the floating-point
/// difference of two input coordinates (one rounding), e.g. x = fl(p - a).
struct DifferenceTriple {
  Eigen::Vector3d x, y, z;
};

/// f(t) = X(t) . (Y(t) x Z(t)) with W(t) = (1 - t) W_t0 + t W_t1, in Bernstein form; error bound
/// covers the rounding of the differences and of every operation.
[[nodiscard]] BernsteinCubic trilinear_determinant(const DifferenceTriple& t0, const DifferenceTriple& t1);

/// trilinear_determinant's error bound alone (the same bits).
[[nodiscard]] double trilinear_error(const DifferenceTriple& t0, const DifferenceTriple& t1);

/// The coefficients with a cheaper error bound, for a first try at a certified sign.
struct TrilinearScreen {
  std::array<double, 4> coefficients{};  ///< trilinear_coefficients, bit for bit
  /// For finite differences: >= trilinear_error whenever it is finite (then no permanent
  /// overflowed; docs/ccd.md, "Screening the coplanarity cubic"), +inf or NaN otherwise.
  double error_upper = 0.0;
  /// Largest |coordinate| of X, Y, Z at t0 and t1 (meaningful when the coefficients are finite).
  double magnitude = 0.0;
};

/// N >= |Y(t) x Z(t)| for all t in [0,1], rounding included.
[[nodiscard]] double cross_norm_bound(const DifferenceTriple& t0, const DifferenceTriple& t1);

/// trilinear_determinant's coefficients alone (the same bits).
inline std::array<double, 4> trilinear_coefficients(
    const DifferenceTriple& t0, const DifferenceTriple& t1) {
  // The blossom of the trilinear det: b_i averages the dets d_ijk = X_i . (Y_j x Z_k) with
  // i + j + k factors taken at t = 1. Each det is evaluated as x0 c0 + x1 c1 + x2 c2, c = y x z,
  // two at a time: lane 0 takes Y_0, lane 1 Y_1.
  const Lanes3 y = lanes3(t0.y, t1.y);
  const Lanes3 z0 = lanes3(t0.z, t0.z);
  const Lanes3 z1 = lanes3(t1.z, t1.z);
  const Lanes3 x0 = lanes3(t0.x, t0.x);
  const Lanes3 x1 = lanes3(t1.x, t1.x);
  const Lanes3 c_z0 = cross(y, z0);  // {Y0 x Z0, Y1 x Z0}
  const Lanes3 c_z1 = cross(y, z1);  // {Y0 x Z1, Y1 x Z1}
  const Lanes d0x0 = dot(x0, c_z0);  // {d000, d010}
  const Lanes d1x0 = dot(x1, c_z0);  // {d100, d110}
  const Lanes d0x1 = dot(x0, c_z1);  // {d001, d011}
  const Lanes d1x1 = dot(x1, c_z1);  // {d101, d111}
  // The middle coefficients {(d100 + d010 + d001) / 3, (d011 + d101 + d110) / 3}, summed in that
  // order.
  const Lanes mid =
      ((Lanes{d1x0[0], d0x1[1]} + Lanes{d0x0[1], d1x1[0]}) + Lanes{d0x1[0], d1x0[1]}) / 3.0;
  return {d0x0[0], mid[0], mid[1], d1x1[1]};
}

/// Coefficients, error_upper and magnitude: the error bound from the largest coordinate
/// magnitudes instead of the permanents (a few flops instead of a third of the cubic). Inline: the
/// differences then stay in registers.
inline TrilinearScreen trilinear_screen(const DifferenceTriple& t0, const DifferenceTriple& t1) {
  TrilinearScreen out;
  out.coefficients = trilinear_coefficients(t0, t1);
  // The largest coordinate magnitudes of X, Y and Z over both times.
  const Lanes mx = max_abs(lanes3(t0.x, t1.x));
  const Lanes my = max_abs(lanes3(t0.y, t1.y));
  const Lanes mz = max_abs(lanes3(t0.z, t1.z));
  const double x = std::max(mx[0], mx[1]), y = std::max(my[0], my[1]), z = std::max(mz[0], mz[1]);
  out.magnitude = std::max({x, y, z});
  // trilinear_error's permanents are built from |x|, |y|, |z| by +, * and /3 only, each rounded
  // to nearest, which is monotone: replaying the same expression tree with every input replaced
  // by its largest magnitude gives a value >= each computed permanent (docs/ccd.md).
  const double q = y * z;
  const double cross_perm = q + q;
  const double r = x * cross_perm;
  const double det_perm = (r + r) + r;
  // The averaged permanents replay to fl(fl(3 d) / 3) <= fl(d (1 + eps)) <= fl(d kRoundUp), also
  // >= d, when 3 d cannot overflow (docs/ccd.md): one product instead of a division.
  const double perm =
      det_perm < 0x1p1020 ? det_perm * kRoundUp : std::numeric_limits<double>::infinity();
  out.error_upper = add_up(rounding_bound(11, perm), times_subnormal_power_of_two<1070>(1.0 + x));
  return out;
}

}  // namespace skelcd::ccd::detail
