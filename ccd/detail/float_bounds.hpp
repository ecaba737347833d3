#pragma once
// Constants and one-line helpers for the rounding-error bounds of ccd/ (derivations in docs/ccd.md,
// "Rounding-error bounds"). IEEE-754 binary64, round to nearest.
//
// Model: fl(a op b) = (a op b)(1 + d), |d| <= kEps, for + - * /, as long as no overflow occurs and no
// product or quotient underflows (sums and differences that land in the subnormal range are exact).
// Products that may underflow are covered by an absolute term (kUnderflowUnit per operation, scaled
// by what multiplies the result afterwards).

#include <bit>
#include <cmath>
#include <cstdint>

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

/// 2^e for -1022 <= e <= 1023, at compile time.
[[nodiscard]] constexpr double power_of_two(int e) {
  double p = 1.0;
  for (; e > 0; --e) p *= 2.0;
  for (; e < 0; ++e) p *= 0.5;
  return p;
}

/// fl(2^-K · y) for y >= 0 (or NaN), K in (1022, 1074]: the underflow terms `m * kUnderflowUnit
/// * (1 + ...)` of the bounds, bit for bit, without a multiplication whose result is subnormal —
/// x86 takes a microcode assist for each of those (about 30 ns here, against 0.5 ns for a normal
/// product), which made one such term the most expensive line of the coplanarity filter.
/// A product below 2^-1022 is a subnormal, the exact y · 2^(1074-K) rounded to an integer (to
/// nearest, ties to even) in units of 2^-1074: adding 2^52 to that value (< 2^52) rounds it the
/// same way, and the integer is then the difference of the bit patterns, which is also the bit
/// pattern of the subnormal (2^52 units is 2^-1022, the smallest normal, when it rounds up). A
/// larger product is a normal number: y · 2^-600 · 2^(600-K), two exact power-of-two scalings.
template <int K>
[[nodiscard]] inline double times_subnormal_power_of_two(double y) {
  static_assert(K > 1022 && K <= 1074);
  constexpr double kToUnits = power_of_two(1074 - K);  // 2^-K in units of 2^-1074
  constexpr double kLimit = power_of_two(K - 1022);    // y · 2^-K < 2^-1022 below this
  if (y >= 0.0 && y < kLimit) {
    const double shifted = y * kToUnits + 0x1p52;
    return std::bit_cast<double>(
        std::bit_cast<std::uint64_t>(shifted) - std::bit_cast<std::uint64_t>(0x1p52));
  }
  return (y * 0x1p-600) * power_of_two(600 - K);
}

/// Error bound of a +,-,* expression evaluated in floating point whose rounding count is at most
/// k (each leaf-to-root chain of a product term sees at most k roundings), given the computed
/// permanent p_hat (the same expression evaluated on absolute values with every - turned into +):
/// |computed - exact| <= k eps P / (1 - k eps) <= fl((k + 1) eps p_hat) for k(k+1) eps < 1/2.
[[nodiscard]] constexpr double rounding_bound(int k, double permanent_hat) {
  return static_cast<double>(k + 1) * kEps * permanent_hat;
}

/// a + b rounded so that the result is >= the exact a + b (a, b >= 0).
[[nodiscard]] inline double add_up(double a, double b) { return (a + b) * kRoundUp; }

/// Smallest double greater than `x` (x finite, not the largest double; ±0 → the smallest positive
/// subnormal). Inline bit arithmetic without branches (std::nextafter is an out-of-line libm call,
/// and a branch on the sign is mispredicted often in per-pair filters): adding 0.0 turns −0 into
/// +0; then one step towards +∞ is +1 on the bits of a non-negative double, −1 on those of a
/// negative one (sign-magnitude: the bits read as int64 are negative exactly for the negative
/// doubles). The one copy for ccd/ and culling/ (culling/dop.hpp).
[[nodiscard]] inline double next_up(double x) {
  const auto bits = std::bit_cast<std::int64_t>(x + 0.0);
  return std::bit_cast<double>(bits + ((bits >> 63) | 1));
}

/// Largest double smaller than `x` (x finite, not the lowest double).
[[nodiscard]] inline double next_down(double x) { return -next_up(-x); }

}  // namespace skelcd::ccd::detail
