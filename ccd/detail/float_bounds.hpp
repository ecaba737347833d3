#pragma once
// Constants and one-line helpers for the rounding-error bounds of ccd/ (derivations in docs/ccd.md,
// "Rounding-error bounds"). IEEE-754 binary64, round to nearest.
//
// Model: fl(a op b) = (a op b)(1 + d), |d| <= kEps, for + - * /, as long as no overflow occurs and no
// product or quotient underflows (sums and differences that land in the subnormal range are exact).
// Products that may underflow are covered by an absolute term (kUnderflowUnit per operation, scaled
// by what multiplies the result afterwards).

#include <cmath>

#if defined(__FAST_MATH__)
#error "ccd/ rounding-error bounds assume IEEE arithmetic: do not build it with -ffast-math"
#endif

namespace skelcd::ccd::detail {

/// Unit roundoff 2^-53.
inline constexpr double kEps = 0x1p-53;
/// 1 + 2^-50: multiplying a positive bound computed with at most 6 roundings by this (and
/// rounding once more) gives a value >= the exact bound, since (1 - kEps)^7 (1 + 8 kEps) > 1.
inline constexpr double kRoundUp = 1.0 + 0x1p-50;
/// Absolute error one underflowing product or quotient can add: half the smallest subnormal, with
/// margin (2^-1074).
inline constexpr double kUnderflowUnit = 0x1p-1074;

/// Error bound of a +,-,* expression evaluated in floating point whose rounding count is at most
/// k (each leaf-to-root chain of a product term sees at most k roundings), given the computed
/// permanent p_hat (the same expression evaluated on absolute values with every - turned into +):
/// |computed - exact| <= k eps P / (1 - k eps) <= fl((k + 1) eps p_hat) for k(k+1) eps < 1/2.
[[nodiscard]] constexpr double rounding_bound(int k, double permanent_hat) {
  return static_cast<double>(k + 1) * kEps * permanent_hat;
}

/// a + b rounded so that the result is >= the exact a + b (a, b >= 0).
[[nodiscard]] inline double add_up(double a, double b) { return (a + b) * kRoundUp; }

}  // namespace skelcd::ccd::detail
