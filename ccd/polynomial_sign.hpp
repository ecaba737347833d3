#pragma once
// Sign of a cubic over the whole closed interval [0,1], decided in floating point with a proven
// rounding-error bound: "positive" and "negative" are certain, "uncertain" is the safe answer.
// Used by the CCD filters (coplanarity of a moving vertex and face, or of two moving edges), and by
// clustering / continuous normal cones (orientation of a moving triangle seen from a moving
// observer). Bounds are derived in docs/ccd.md ("Sign of a cubic on [0,1]").

#include <array>
#include <cstdint>

#include <Eigen/Core>

namespace skelcd::ccd {

enum class PolynomialSign : std::int8_t {
  negative = -1,  ///< f(t) < 0 for every t in [0,1], proven
  uncertain = 0,  ///< not proven either way (f may have a root in [0,1])
  positive = 1,   ///< f(t) > 0 for every t in [0,1], proven
};

/// f(t) = sum_i coefficients[i] * C(3,i) t^i (1-t)^(3-i): a cubic in Bernstein form on [0,1].
/// Every stored coefficient is within `error` (absolute, >= 0) of the exact one.
struct BernsteinCubic {
  std::array<double, 4> coefficients{};
  double error = 0.0;
};

/// f(t) = c[0] + c[1] t + c[2] t^2 + c[3] t^3; every stored coefficient within `error` of the exact one.
struct PowerCubic {
  std::array<double, 4> coefficients{};
  double error = 0.0;
};

/// Bernstein coefficients of a power-form cubic, the error bound carried through.
[[nodiscard]] BernsteinCubic to_bernstein(const PowerCubic& f);
/// Power coefficients of a Bernstein-form cubic, the error bound carried through.
[[nodiscard]] PowerCubic to_power(const BernsteinCubic& f);
/// The cubic through the values f(0), f(1/3), f(2/3), f(1), each within `value_error` of the exact
/// value.
[[nodiscard]] BernsteinCubic bernstein_from_values(
    const std::array<double, 4>& values,
    double value_error = 0.0);

/// Sign of f over all of [0,1]. Bernstein coefficients bound the cubic (convex-hull property); if
/// they do not all clear the error bound, the interval is halved (de Casteljau, error bound
/// carried through) up to `max_subdivisions` levels deep.
/// @note Never a wrong certain answer, for any finite input; non-finite input gives uncertain.
[[nodiscard]] PolynomialSign cubic_sign(const BernsteinCubic& f, int max_subdivisions = 4);
[[nodiscard]] PolynomialSign cubic_sign(const PowerCubic& f, int max_subdivisions = 4);

/// A triangle (a, b, c) and an observer point q, all moving linearly over t in [0,1].
struct MovingOrientationQuery {
  Eigen::Vector3d a_t0, b_t0, c_t0, q_t0;  ///< at t = 0
  Eigen::Vector3d a_t1, b_t1, c_t1, q_t1;  ///< at t = 1
};

/// The cubic f(t) = (a(t) - q(t)) . n(t), n = (b - a) x (c - a): positive when the observer q is
/// behind the triangle (on the side its normal points away from), negative in front, zero when
/// coplanar or the triangle is degenerate. Bernstein coefficients are computed from the trilinear
/// form (no power-basis detour), with the rounding-error bound of docs/ccd.md.
[[nodiscard]] BernsteinCubic moving_orientation_cubic(const MovingOrientationQuery& query);

/// cubic_sign(moving_orientation_cubic(query), max_subdivisions), the same answer for every
/// query, cheaper when the sign is clear: the coefficients' hull is first tried with the error
/// bound of the CCD coplanarity screen (from the largest coordinate magnitudes, docs/ccd.md
/// "Screening the coplanarity cubic"), which is at least the exact bound whenever that is finite;
/// a sign it certifies is the one cubic_sign certifies at its first test. Otherwise the exact
/// bound and cubic_sign, as before.
[[nodiscard]] PolynomialSign moving_orientation_sign(
    const MovingOrientationQuery& query, int max_subdivisions = 4);

/// Bound N with |n(t)| <= N for all t in [0,1], n(t) = (b(t) - a(t)) x (c(t) - a(t)) (rounding
/// included). Used to turn a distance into a bound on the orientation cubic.
[[nodiscard]] double moving_normal_bound(const MovingOrientationQuery& query);

}  // namespace skelcd::ccd
