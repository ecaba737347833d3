// A triangle's swept volume over an interval from its six corner positions (its three corners at
// both ends), bit for bit on SSE2 lanes and in scalar code: FeatureBounds::swept_triangles stores
// it by triangle id, Bvh::refit_swept rounds it into the slots without storing it.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "culling/dop.hpp"

namespace skelcd::culling::detail {

#if defined(__SSE2__)

/// ccd::detail::next_up of two doubles, bit for bit.
inline __m128d next_up2(__m128d x) {
  const __m128i bits = _mm_castpd_si128(_mm_add_pd(x, _mm_setzero_pd()));
  // bits >> 63 of each 64-bit lane: the sign of its upper half, in both halves.
  const __m128i sign = _mm_shuffle_epi32(_mm_srai_epi32(bits, 31), _MM_SHUFFLE(3, 3, 1, 1));
  return _mm_castsi128_pd(_mm_add_epi64(bits, _mm_or_si128(sign, _mm_set1_epi64x(1))));
}

/// ccd::detail::next_down of two doubles, bit for bit (−next_up(−x)).
inline __m128d next_down2(__m128d x) {
  const __m128d minus = _mm_set1_pd(-0.0);
  return _mm_xor_pd(next_up2(_mm_xor_pd(x, minus)), minus);
}

/// FeatureBounds<N>::swept_triangles' volume of the six corner positions `c` (a triangle's at
/// both ends) on SSE2 lanes, bit for bit the scalar loop's: the same sums and differences, each
/// one rounding, met in the same order by the same selects (minpd(s, lo) is (s < lo) ? s : lo,
/// std::min(lo, s)), the same steps outwards on the diagonals. The coordinates in (x, y) and (z);
/// Dop<8>'s diagonals as (x + y, x + z), (y + z) and (x − y, x − z).
template <int N>
inline void swept_corners_sse2(const std::array<const double*, 6>& c, Dop<N>& d) {
  static_assert(N == 3 || N == 8);
  __m128d lo_xy = _mm_loadu_pd(c[0]);
  __m128d lo_z = _mm_load_sd(c[0] + 2);
  __m128d hi_xy = lo_xy;
  __m128d hi_z = lo_z;
  const auto diagonals =
      [](__m128d xy, __m128d z, __m128d& sums, __m128d& differences, __m128d& y_plus_z) {
        const __m128d xx = _mm_unpacklo_pd(xy, xy);
        const __m128d yz = _mm_shuffle_pd(xy, z, 1);
        sums = _mm_add_pd(xx, yz);
        differences = _mm_sub_pd(xx, yz);
        y_plus_z = _mm_add_sd(_mm_unpackhi_pd(xy, xy), z);
      };
  [[maybe_unused]] __m128d lo_s = _mm_setzero_pd();
  [[maybe_unused]] __m128d lo_d = _mm_setzero_pd();
  [[maybe_unused]] __m128d lo_yz = _mm_setzero_pd();
  if constexpr (N == 8) diagonals(lo_xy, lo_z, lo_s, lo_d, lo_yz);
  [[maybe_unused]] __m128d hi_s = lo_s, hi_d = lo_d, hi_yz = lo_yz;
  for (std::size_t m = 1; m < 6; ++m) {
    const __m128d xy = _mm_loadu_pd(c[m]);
    const __m128d z = _mm_load_sd(c[m] + 2);
    lo_xy = _mm_min_pd(xy, lo_xy);
    hi_xy = _mm_max_pd(xy, hi_xy);
    lo_z = _mm_min_sd(z, lo_z);
    hi_z = _mm_max_sd(z, hi_z);
    if constexpr (N == 8) {
      __m128d s, dd, yz;
      diagonals(xy, z, s, dd, yz);
      lo_s = _mm_min_pd(s, lo_s);
      hi_s = _mm_max_pd(s, hi_s);
      lo_d = _mm_min_pd(dd, lo_d);
      hi_d = _mm_max_pd(dd, hi_d);
      lo_yz = _mm_min_sd(yz, lo_yz);
      hi_yz = _mm_max_sd(yz, hi_yz);
    }
  }
  _mm_storeu_pd(&d.lo[0], lo_xy);
  _mm_store_sd(&d.lo[2], lo_z);
  _mm_storeu_pd(&d.hi[0], hi_xy);
  _mm_store_sd(&d.hi[2], hi_z);
  if constexpr (N == 8) {
    // Dop<8>'s axes 3..7: x + y, x + z, y + z, x − y, x − z.
    _mm_storeu_pd(&d.lo[3], next_down2(lo_s));
    _mm_store_sd(&d.lo[5], next_down2(lo_yz));
    _mm_storeu_pd(&d.lo[6], next_down2(lo_d));
    _mm_storeu_pd(&d.hi[3], next_up2(hi_s));
    _mm_store_sd(&d.hi[5], next_up2(hi_yz));
    _mm_storeu_pd(&d.hi[6], next_up2(hi_d));
  }
}

#endif

/// The scalar form of swept_corners_sse2: the coordinates' extremes over the
/// six corners, and Dop<8>'s diagonals as sums or differences of two coordinates, one rounding
/// each, so that the exact value lies within one ulp of the rounded one.
template <int N>
inline void swept_corners_scalar(const std::array<const double*, 6>& c, Dop<N>& d) {
  for (std::size_t a = 0; a < 3; ++a) {
    double lo = c[0][a];
    double hi = lo;
    for (std::size_t k = 1; k < 6; ++k) {
      lo = std::min(lo, c[k][a]);
      hi = std::max(hi, c[k][a]);
    }
    d.lo[a] = lo;
    d.hi[a] = hi;
  }
  for (std::size_t k = 3; k < static_cast<std::size_t>(N); ++k) {
    const auto& axis = DopAxes<N>::kAxes[k];
    const std::size_t i = axis[0] != 0 ? 0 : 1;
    const std::size_t j = axis[2] != 0 ? 2 : 1;
    const double si = axis[i];
    const double sj = axis[j];
    double lo = si * c[0][i] + sj * c[0][j];
    double hi = lo;
    for (std::size_t m = 1; m < 6; ++m) {
      const double s = si * c[m][i] + sj * c[m][j];
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    d.lo[k] = next_down(lo);
    d.hi[k] = next_up(hi);
  }
}

/// The swept volume of the six corner positions `c` (a triangle's three corners at both ends):
/// exact on the coordinate axes, each diagonal one step outwards from its one rounding.
template <int N>
inline void swept_corners(const std::array<const double*, 6>& c, Dop<N>& d) {
#if defined(__SSE2__)
  swept_corners_sse2(c, d);
#else
  swept_corners_scalar(c, d);
#endif
}

}  // namespace skelcd::culling::detail
