#pragma once
// The algebraic stage of conservative CCD (docs/ccd.md, "The algebraic filter"): the exact
// algorithm's logic in floating point with certified Bernstein bounds.
//
// Contact at time t needs the coplanarity cubic c(t) = 0 and every "inside" quartic g_i(t) >= 0
// (vertex-face: n . ((b - a) x (p - a)) and its two rotations; edge-edge: the numerators of the two
// segment parameters and their complements). These are necessary for every configuration,
// degenerate ones included (there the g_i vanish). [0,1] is halved depth first, earliest first:
//  - c certified nonzero on an interval, or some g_i certified negative: no contact there;
//  - c certified to change sign on I and every g_i certified positive: a contact in I, for sure;
//  - neither, when the interval cannot be refined further: undecided from that interval's start
//    (everything before it has been excluded) — the caller runs the inclusion solver from there.

#include <array>
#include <cstdint>

#include <Eigen/Core>

#include "ccd/polynomial_sign.hpp"

namespace skelcd::ccd::detail {

/// f(t) = sum_i coefficients[i] * C(4,i) t^i (1-t)^(4-i), each coefficient within `error`.
struct BernsteinQuartic {
  std::array<double, 5> coefficients{};
  double error = 0.0;
};

/// Four linearly moving difference vectors at t = 0 and t = 1 (each coordinate one floating-point
/// subtraction of two input coordinates).
struct QuadrupleDifferences {
  Eigen::Vector3d a_t0, b_t0, c_t0, d_t0;
  Eigen::Vector3d a_t1, b_t1, c_t1, d_t1;
};

/// (A(t) x B(t)) . (C(t) x D(t)) in Bernstein form on [0,1], with its rounding-error bound.
[[nodiscard]] BernsteinQuartic cross_dot_quartic(const QuadrupleDifferences& q);

/// cross_dot_quartic of q0 into g0 and of q1 into g1, bit for bit, computed together (each vector
/// operation does one step of both), about half the cost of two calls.
/// @pre every coordinate of q0 and q1 is finite (the largest magnitude, which enters the
/// underflow term, is then the same whatever order it is found in).
void cross_dot_quartic_pair(
    const QuadrupleDifferences& q0,
    const QuadrupleDifferences& q1,
    BernsteinQuartic& g0,
    BernsteinQuartic& g1);

/// The inside quartics of a query, for inside_quartics_x4.
enum class InsideQuartics : std::uint8_t {
  /// Points (v, f0, f1, f2): (y x z) . (y x x), (y x z) . ((f2 - f1) x (v - f1)),
  /// (y x z) . ((f0 - f2) x (v - f2)) with x = v - f0, y = f1 - f0, z = f2 - f0, the fourth lane
  /// repeating the third (vertex_face.cpp).
  vertex_face,
  /// Points (a0, a1, b0, b1): (w x d_b) . n, ((a1 - b0) x d_b) . n, (w x d_a) . n,
  /// (d_a x (b1 - a0)) . n with w = b0 - a0, d_a = a1 - a0, d_b = b1 - b0, n = d_a x d_b
  /// (edge_edge.cpp).
  edge_edge,
};

/// The quadruples named above from the query's four points at t = 0 (`at_t0`) and t = 1, each
/// difference one subtraction of two points, into q[0..4) (with three, q[3] repeats q[2]).
/// Returns how many quartics the query has (3 or 4). The one definition the kernels and
/// inside_quartics_x4 build them from.
int inside_quadruples(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    QuadrupleDifferences* q);

/// The inside quartics of one query straight from its four points at t = 0 (`at_t0`) and t = 1,
/// bit for bit cross_dot_quartic of the QuadrupleDifferences named above (each difference the
/// same single subtraction). Where cross_dot_quartics_x4_wide(), one AVX2 evaluation: the
/// differences taken four lanes at a time, and the factor pair every quartic of the query shares
/// (n's) crossed once instead of once per quartic; otherwise the quadruples, two quartics at a
/// time. Returns how many quartics the query has (3 or 4; g[3] is written either way).
/// @pre every coordinate of the quadruples finite.
int inside_quartics_x4(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    BernsteinQuartic* g);

/// Four quartics side by side, as the four-lane code holds them: coefficient k of quartic `lane`
/// in coefficients[k][lane], its bound in error[lane].
struct QuarticLanes {
  alignas(32) std::array<std::array<double, 4>, 5> coefficients;
  alignas(32) std::array<double, 4> error;
};

/// inside_quartics_x4's AVX2 evaluation, its quartics left in lanes for algebraic_filter_lanes
/// (no scattering into BernsteinQuartic records and gathering back). Returns the count (3 or 4;
/// with 3, lane 3 repeats lane 2). @pre cross_dot_quartics_x4_wide(), and the coordinates as for
/// inside_quartics_x4.
int inside_quartic_lanes(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    QuarticLanes& g);

/// Whether the quartics are computed four at once (inside_quartics_x4, inside_quartic_lanes and
/// the four-lane filter: AVX2, and not forced to the baseline): four then cost what two do.
[[nodiscard]] bool cross_dot_quartics_x4_wide();

/// For the tests: true makes the quartics and their filter take the baseline paths even on a CPU
/// with AVX2; false lets them choose again.
void force_baseline_quartics(bool baseline);

enum class AlgebraicOutcome : std::uint8_t { separated, contact, undecided };

struct AlgebraicVerdict {
  AlgebraicOutcome outcome = AlgebraicOutcome::undecided;
  /// contact: the first contact lies in [t_lo, t_hi]. undecided: no contact before t_lo.
  double t_lo = 0.0;
  double t_hi = 1.0;
};

/// Runs the interval logic above on c and the `count` quartics g[0..count).
/// @param toi_tolerance a certain contact's bracket is narrowed to this width when the cubic's sign
/// allows. @note No allocation, no throw.
[[nodiscard]] AlgebraicVerdict algebraic_filter(
    const BernsteinCubic& c,
    const BernsteinQuartic* g,
    int count,
    double toi_tolerance);

/// algebraic_filter on quartics in lanes (inside_quartic_lanes): the same verdict, bit for bit,
/// as on the same quartics as records. @pre cross_dot_quartics_x4_wide(), count 3 or 4, and with
/// 3 lane 3 repeating lane 2.
[[nodiscard]] AlgebraicVerdict algebraic_filter_lanes(
    const BernsteinCubic& c, const QuarticLanes& g, int count, double toi_tolerance);

}  // namespace skelcd::ccd::detail
