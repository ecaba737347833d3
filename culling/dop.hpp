#pragma once
// Discrete oriented polytopes (k-DOPs) with a fixed set of slab axes: the bounding volumes of the
// baseline hierarchies. Dop<3> is the axis-aligned box (AABB), Dop<8> the 16-DOP.
//
// Conservative in floating point: the interval stored on each axis contains the *exact*
// projection of every point the volume was built from. Coordinate axes need no rounding (min/max
// of doubles is exact); the diagonal axes of the 16-DOP sum two coordinates, and the rounding
// error of that sum is recovered exactly (TwoSum) and the bound moved out by one ulp when it is
// not zero. Inflation by a distance is rounded outwards as well. See docs/culling.md.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "ccd/detail/float_bounds.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace skelcd::culling {

/// Smallest double greater than `x`, largest smaller (x finite; bit arithmetic without branches):
/// the one copy in ccd/detail/float_bounds.hpp, which the CCD kernels' relative boxes use too.
using ccd::detail::next_down;
using ccd::detail::next_up;

/// The largest float not above `x` (x finite): bounds rounded outwards for the traversal's float
/// volumes (culling/bvh.hpp). Never a subnormal, so that the bound holds also where the CPU
/// flushes subnormals to zero: a result in (0, FLT_MIN) becomes 0, in (−FLT_MIN, 0) −FLT_MIN.
[[nodiscard]] inline float float_below(double x) {
  constexpr float kMin = std::numeric_limits<float>::min();
  const float f = static_cast<float>(x);  // nearest (±inf beyond the float range)
  // One step down when rounding went up, as next_down on the bits of a float (+inf steps to the
  // largest float); a select rather than a branch: rounding goes up about half the time.
  const auto bits = std::bit_cast<std::int32_t>(-f + 0.0f);
  const float below = -std::bit_cast<float>(bits + ((bits >> 31) | 1));
  // Selects on the bits: compilers turn a ?: on floats into a branch, which mispredicts on
  // coordinates (the refit converts six per triangle).
  const auto pick = [](bool c, float a, float b) {
    const auto ia = std::bit_cast<std::int32_t>(a);
    const auto ib = std::bit_cast<std::int32_t>(b);
    return std::bit_cast<float>(ib ^ ((ia ^ ib) & -static_cast<std::int32_t>(c)));
  };
  const float r = pick(static_cast<double>(f) > x, below, f);
  return pick(r > -kMin && r < kMin, pick(x >= 0.0, 0.0f, -kMin), r);
}

/// The smallest float not below `x` (x finite), never a subnormal (as float_below).
[[nodiscard]] inline float float_above(double x) { return -float_below(-x); }

/// The slab axes of Dop<N> (not normalised; integer components).
/// - N = 3 (AABB): x, y, z.
/// - N = 8 (16-DOP): x, y, z, x+y, x+z, y+z, x−y, x−z — the three coordinate axes and five of the
///   six face diagonals, the convention of FCL's KDOP<16> (Klosowski et al. 1998 use 6/14/18/26;
///   a 16-DOP cannot be symmetric under the cube's rotations, so some choice of five is needed).
template <int N>
struct DopAxes;

template <>
struct DopAxes<3> {
  static constexpr std::array<std::array<int, 3>, 3> kAxes{{{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}};
};

template <>
struct DopAxes<8> {
  static constexpr std::array<std::array<int, 3>, 8> kAxes{
      {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 0}, {1, 0, 1}, {0, 1, 1}, {1, -1, 0}, {1, 0, -1}}};
};

namespace detail {

/// [lo, hi] containing the exact a + b (a, b finite): TwoSum recovers the rounding error e of
/// s = fl(a + b) exactly (s + e == a + b), so the bound moves one ulp only on the side of e.
inline void bracket_sum(double a, double b, double& lo, double& hi) {
  const double s = a + b;
  const double bb = s - a;
  const double e = (a - (s - bb)) + (b - bb);
  lo = e < 0.0 ? next_down(s) : s;
  hi = e > 0.0 ? next_up(s) : s;
}

}  // namespace detail

/// A k-DOP: on each of N axes the closed interval [lo, hi] of projections of the bounded set.
template <int N>
struct Dop {
  static constexpr int kAxes = N;
  std::array<double, static_cast<std::size_t>(N)> lo;
  std::array<double, static_cast<std::size_t>(N)> hi;

  /// The empty volume (lo = +inf, hi = -inf on every axis): the identity of merge().
  [[nodiscard]] static Dop empty() {
    Dop d;
    d.lo.fill(std::numeric_limits<double>::infinity());
    d.hi.fill(-std::numeric_limits<double>::infinity());
    return d;
  }

  /// The volume of one point, each projection bracketed outwards (exact on coordinate axes).
  [[nodiscard]] static Dop of_point(double x, double y, double z);
  [[nodiscard]] static Dop of_point(const Eigen::Vector3d& p) {
    return of_point(p.x(), p.y(), p.z());
  }

  /// Grows this volume to contain `other`.
  void merge(const Dop& other) {
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      lo[k] = std::min(lo[k], other.lo[k]);
      hi[k] = std::max(hi[k], other.hi[k]);
    }
  }

  /// True when the closed volumes share a point on every axis (touching counts).
  [[nodiscard]] bool overlaps(const Dop& other) const {
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      if (lo[k] > other.hi[k] || other.lo[k] > hi[k]) return false;
    }
    return true;
  }

  /// True when `other` lies inside this volume on every axis.
  [[nodiscard]] bool contains(const Dop& other) const {
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      if (other.lo[k] < lo[k] || other.hi[k] > hi[k]) return false;
    }
    return true;
  }

  /// Grows every slab by `half_width` times the axis length (so two volumes inflated by d/2
  /// overlap whenever the sets they bound come within Euclidean distance d), rounded outwards.
  /// @pre half_width >= 0; the volume is not empty and finite.
  void inflate(double half_width);
};

using Aabb = Dop<3>;
using Kdop16 = Dop<8>;

template <>
inline Dop<3> Dop<3>::of_point(double x, double y, double z) {
  Dop<3> d;
  d.lo = {x, y, z};
  d.hi = {x, y, z};
  return d;
}

template <>
inline Dop<8> Dop<8>::of_point(double x, double y, double z) {
  Dop<8> d;
  d.lo[0] = d.hi[0] = x;
  d.lo[1] = d.hi[1] = y;
  d.lo[2] = d.hi[2] = z;
  detail::bracket_sum(x, y, d.lo[3], d.hi[3]);
  detail::bracket_sum(x, z, d.lo[4], d.hi[4]);
  detail::bracket_sum(y, z, d.lo[5], d.hi[5]);
  detail::bracket_sum(x, -y, d.lo[6], d.hi[6]);
  detail::bracket_sum(x, -z, d.lo[7], d.hi[7]);
  return d;
}

template <int N>
void Dop<N>::inflate(double half_width) {
  assert(half_width >= 0.0);
  if (half_width == 0.0) return;
  // Axis k has length |a_k| = sqrt(number of non-zero components) (components are 0 or ±1);
  // the slab grows by an upper bound of half_width·|a_k|, and each end is rounded outwards.
  for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
    const auto& axis = DopAxes<N>::kAxes[k];
    const int nonzero = (axis[0] != 0) + (axis[1] != 0) + (axis[2] != 0);
    double grow = half_width;
    if (nonzero > 1) grow = next_up(half_width * next_up(std::sqrt(static_cast<double>(nonzero))));
    lo[k] = next_down(lo[k] - grow);
    hi[k] = next_up(hi[k] + grow);
  }
}

#if defined(__SSE2__)
namespace detail {

/// float_below of four doubles (x01: lanes 0, 1; x23: lanes 2, 3), bit for bit: the same steps on
/// SSE2 lanes — the nearest float, one step down where rounding went up, subnormals replaced.
inline __m128 float_below4(__m128d x01, __m128d x23) {
  const __m128 sign = _mm_set1_ps(-0.0f);
  const __m128 f = _mm_movelh_ps(_mm_cvtpd_ps(x01), _mm_cvtpd_ps(x23));
  // Four 64-bit masks to four 32-bit lanes.
  const auto pack = [](__m128d m01, __m128d m23) {
    return _mm_shuffle_ps(_mm_castpd_ps(m01), _mm_castpd_ps(m23), _MM_SHUFFLE(2, 0, 2, 0));
  };
  const __m128 went_up = pack(
      _mm_cmpgt_pd(_mm_cvtps_pd(f), x01), _mm_cmpgt_pd(_mm_cvtps_pd(_mm_movehl_ps(f, f)), x23));
  __m128i bits = _mm_castps_si128(_mm_add_ps(_mm_xor_ps(f, sign), _mm_setzero_ps()));  // −f + 0
  bits = _mm_add_epi32(bits, _mm_or_si128(_mm_srai_epi32(bits, 31), _mm_set1_epi32(1)));
  const __m128 below = _mm_xor_ps(_mm_castsi128_ps(bits), sign);
  const __m128 r = _mm_or_ps(_mm_and_ps(went_up, below), _mm_andnot_ps(went_up, f));
  const __m128 k_min = _mm_set1_ps(std::numeric_limits<float>::min());
  const __m128 tiny = _mm_and_ps(_mm_cmpgt_ps(r, _mm_xor_ps(k_min, sign)), _mm_cmplt_ps(r, k_min));
  const __m128 non_negative =
      pack(_mm_cmpge_pd(x01, _mm_setzero_pd()), _mm_cmpge_pd(x23, _mm_setzero_pd()));
  const __m128 replacement = _mm_andnot_ps(non_negative, _mm_xor_ps(k_min, sign));  // 0 or −min
  return _mm_or_ps(_mm_and_ps(tiny, replacement), _mm_andnot_ps(tiny, r));
}

}  // namespace detail
#endif

/// The volume v rounded outwards to floats, bit for bit float_below(v.lo[k]) and
/// float_above(v.hi[k]) — four at a time where SSE2 is there (a refit converts every triangle's).
template <int N>
inline void round_outwards(
    const Dop<N>& v,
    std::array<float, static_cast<std::size_t>(N)>& lo,
    std::array<float, static_cast<std::size_t>(N)>& hi) {
  constexpr auto kN = static_cast<std::size_t>(N);
#if defined(__SSE2__)
  // lo, then −hi (float_above(h) = −float_below(−h)), in groups of four, loaded from the volume
  // itself where its layout gives them (lo[0..N) then hi[0..N), contiguous): filled through a
  // buffer instead, each group's 16-byte loads waited for the 8-byte stores before them (no store
  // forwarding across two stores), a fifth of the AABB refit's cycles.
  static_assert(
      std::is_standard_layout_v<Dop<N>> && offsetof(Dop<N>, hi) == kN * sizeof(double) &&
      sizeof(Dop<N>) == 2 * kN * sizeof(double));
  const __m128d minus = _mm_set1_pd(-0.0);
  if constexpr (kN % 4 == 0) {
    for (std::size_t g = 0; g < kN; g += 4) {
      _mm_storeu_ps(
          lo.data() + g,
          detail::float_below4(_mm_loadu_pd(v.lo.data() + g), _mm_loadu_pd(v.lo.data() + g + 2)));
      _mm_storeu_ps(
          hi.data() + g,
          _mm_xor_ps(
              detail::float_below4(
                  _mm_xor_pd(_mm_loadu_pd(v.hi.data() + g), minus),
                  _mm_xor_pd(_mm_loadu_pd(v.hi.data() + g + 2), minus)),
              _mm_set1_ps(-0.0f)));
    }
    return;
  } else if constexpr (kN == 3) {
    // (lo0, lo1 | lo2, −hi0) and (−hi1, −hi2 | 0, 0): the pairs at lo, lo + 2 and hi + 1.
    alignas(16) std::array<float, 8> out;
    const auto* d = reinterpret_cast<const double*>(&v);  // lo0 lo1 lo2 hi0 hi1 hi2
    _mm_store_ps(
        out.data(),
        detail::float_below4(
            _mm_loadu_pd(d), _mm_xor_pd(_mm_loadu_pd(d + 2), _mm_set_pd(-0.0, 0.0))));
    _mm_store_ps(
        out.data() + 4,
        detail::float_below4(_mm_xor_pd(_mm_loadu_pd(d + 4), minus), _mm_setzero_pd()));
    lo = {out[0], out[1], out[2]};
    hi = {-out[3], -out[4], -out[5]};
    return;
  }
  constexpr std::size_t kGroups = (2 * kN + 3) / 4;
  alignas(16) std::array<double, 4 * kGroups> in{};
  alignas(16) std::array<float, 4 * kGroups> out{};
  for (std::size_t k = 0; k < kN; ++k) {
    in[k] = v.lo[k];
    in[kN + k] = -v.hi[k];
  }
  for (std::size_t g = 0; g < kGroups; ++g) {
    _mm_store_ps(
        out.data() + 4 * g,
        detail::float_below4(_mm_load_pd(in.data() + 4 * g), _mm_load_pd(in.data() + 4 * g + 2)));
  }
  for (std::size_t k = 0; k < kN; ++k) {
    lo[k] = out[k];
    hi[k] = -out[kN + k];
  }
#else
  for (std::size_t k = 0; k < kN; ++k) {
    lo[k] = float_below(v.lo[k]);
    hi[k] = float_above(v.hi[k]);
  }
#endif
}

}  // namespace skelcd::culling
