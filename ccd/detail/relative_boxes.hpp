#pragma once
// The relative stage of the conservative pipeline (docs/ccd.md, "Relative boxes" and its
// "Directions apart at both ends").
//
// Without a contact distance: directions apart at both ends. For a fixed direction n, each point's
// projection p(t)·n is linear in t, so min over one feature's points minus max over the other's is
// concave in t (a minimum of linear functions minus a maximum of them). Positive at t = 0 and at
// t = 1, it is positive on all of [0, 1]: the two hulls, hence the features, stay on the two sides
// of a plane normal to n at every instant. The stage tries the three axes and the six diagonals
// x ± y, y ± z, z ± x. Each projection is one coordinate or one rounded sum of two, and rounding
// is monotone (x < y whenever fl(x) < fl(y), overflow to ±inf included), so a strict gap between
// the rounded projections is a gap between the exact ones.
//
// With a contact distance: the relative boxes. Subtracting t·u from every point of a vertex-face
// or edge-edge query changes no distance between them at any instant t, and a point moving
// linearly from p₀ to p₁ moves, less t·u, inside the box of p₀ and p₁ − u. So when the boxes of the
// two features' relative ends, each grown by half of min_separation, are apart on some axis, the
// features never come within min_separation of each other over [0, 1]. Any u is sound; u is the
// mean displacement of the query's four points. Each p₁ − u is bracketed by the doubles around its
// rounded value (round-to-nearest is within half an ulp), so the boxes hold the exact relative
// ends.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "ccd/detail/float_bounds.hpp"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace skelcd::ccd::detail {

/// relative_boxes_apart with (kWidth: half_width > 0) or without a contact distance. The pipeline
/// asks it only with one (relative_stage_apart); without, ends_apart removes every query it would
/// and more.
template <std::size_t NA, bool kWidth>
[[nodiscard]] bool relative_boxes_apart_as(
    const std::array<const Eigen::Vector3d*, 4>& t0,
    const std::array<const Eigen::Vector3d*, 4>& t1,
    double half_width) {
  constexpr double kMax = std::numeric_limits<double>::max();
  const Eigen::Vector3d u =
      0.25 * (((*t1[0] - *t0[0]) + (*t1[1] - *t0[1])) + ((*t1[2] - *t0[2]) + (*t1[3] - *t0[3])));
  // A non-finite coordinate anywhere makes some component of u non-finite: such queries are
  // answered by the rest of the pipeline (a hit, as documented), whatever one axis shows.
  if (!(std::abs(u[0]) <= kMax && std::abs(u[1]) <= kMax && std::abs(u[2]) <= kMax)) return false;
  for (Eigen::Index k = 0; k < 3; ++k) {
    double lo[2], hi[2];
    bool finite = true;
    for (std::size_t side = 0; side < 2; ++side) {
      const std::size_t begin = side == 0 ? 0 : NA;
      const std::size_t end = side == 0 ? NA : 4;
      double l = (*t0[begin])[k];
      double h = l;
      for (std::size_t i = begin; i < end; ++i) {
        const double p0 = (*t0[i])[k];
        const double p1 = (*t1[i])[k] - u[k];
        finite = finite && std::abs(p0) <= kMax && std::abs(p1) <= kMax;
        l = std::min({l, p0, kWidth ? next_down(p1) : p1});
        h = std::max({h, p0, kWidth ? next_up(p1) : p1});
      }
      if constexpr (kWidth) {
        l -= half_width;
        h += half_width;
        finite = finite && std::abs(l) <= kMax && std::abs(h) <= kMax;
        l = next_down(l);
        h = next_up(h);
      }
      lo[side] = l;
      hi[side] = h;
    }
    // NaN never passes the finiteness checks; an infinite step result is only ±inf itself.
    if (finite && (hi[0] < lo[1] || hi[1] < lo[0])) return true;
  }
  return false;
}

/// True when the relative boxes of the features (a: the first NA points, b: the other 4 − NA)
/// prove that they never come within 2·half_width over the interval. `t0` and `t1` list the four
/// points, a's first. False whenever a value on the way is not finite (a non-finite coordinate, an
/// overflowing difference): the stage then leaves the query to the rest of the pipeline.
/// @pre half_width >= 0.
template <std::size_t NA>
[[nodiscard]] bool relative_boxes_apart(
    const std::array<const Eigen::Vector3d*, 4>& t0,
    const std::array<const Eigen::Vector3d*, 4>& t1,
    double half_width) {
  return half_width > 0.0 ? relative_boxes_apart_as<NA, true>(t0, t1, half_width)
                          : relative_boxes_apart_as<NA, false>(t0, t1, half_width);
}

/// Whether one of three directions separates the features (a: the first NA points, b: the other
/// 4 − NA) strictly at t = 0 and at t = 1, the same way round at both; `project` maps a point to
/// its three rounded projections.
template <std::size_t NA, typename Project>
[[nodiscard]] bool ends_apart_on(
    const std::array<const Eigen::Vector3d*, 4>& t0,
    const std::array<const Eigen::Vector3d*, 4>& t1,
    Project&& project) {
  // lo/hi[time][side][direction] of the rounded projections.
  double lo[2][2][3];
  double hi[2][2][3];
  for (std::size_t time = 0; time < 2; ++time) {
    const auto& points = time == 0 ? t0 : t1;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::array<double, 3> v = project(*points[i]);
      const std::size_t side = i < NA ? 0 : 1;
      const bool first = i == 0 || i == NA;
      for (std::size_t d = 0; d < 3; ++d) {
        lo[time][side][d] = first ? v[d] : std::min(lo[time][side][d], v[d]);
        hi[time][side][d] = first ? v[d] : std::max(hi[time][side][d], v[d]);
      }
    }
  }
  bool apart = false;
  for (std::size_t d = 0; d < 3; ++d) {
    const bool below = hi[0][0][d] < lo[0][1][d] && hi[1][0][d] < lo[1][1][d];
    const bool above = hi[0][1][d] < lo[0][0][d] && hi[1][1][d] < lo[1][0][d];
    apart = apart || below || above;
  }
  return apart;
}

/// True when one of nine directions — x, y, z, x + y, y + z, z + x, x − y, y − z, z − x — separates
/// the features (a: the first NA points, b: the other 4 − NA) strictly at t = 0 and at t = 1, the
/// same way round at both: they then never touch over [0, 1] (the header's argument). False
/// whenever a coordinate is not finite: such queries go on to the rest of the pipeline (a hit, as
/// documented).
template <std::size_t NA>
[[nodiscard]] bool ends_apart(
    const std::array<const Eigen::Vector3d*, 4>& t0,
    const std::array<const Eigen::Vector3d*, 4>& t1) {
  static_assert(NA >= 1 && NA <= 3);
#if defined(__SSE2__)
  // Two directions a register: (x, y), (z, z), then (x + y, y + z), (x − y, y − z), (z + x, z − x)
  // — z − x as z + (−x), the same rounding — when the axes did not separate. x − x is 0 for a
  // finite x and NaN otherwise, so their sum over the query says whether every coordinate is
  // finite.
  const __m128d negate_high = _mm_set_pd(-0.0, 0.0);
  __m128d zeros = _mm_setzero_pd();
  const auto apart_on = [&]<std::size_t kRegisters>(auto&& registers) {
    __m128d lo[2][2][kRegisters];
    __m128d hi[2][2][kRegisters];
    for (std::size_t time = 0; time < 2; ++time) {
      const auto& points = time == 0 ? t0 : t1;
      for (std::size_t i = 0; i < 4; ++i) {
        __m128d v[kRegisters];
        registers(points[i]->data(), v);
        const std::size_t side = i < NA ? 0 : 1;
        const bool first = i == 0 || i == NA;
        for (std::size_t r = 0; r < kRegisters; ++r) {
          lo[time][side][r] = first ? v[r] : _mm_min_pd(lo[time][side][r], v[r]);
          hi[time][side][r] = first ? v[r] : _mm_max_pd(hi[time][side][r], v[r]);
        }
      }
    }
    __m128d apart = _mm_setzero_pd();
    for (std::size_t r = 0; r < kRegisters; ++r) {
      const __m128d below = _mm_and_pd(
          _mm_cmplt_pd(hi[0][0][r], lo[0][1][r]), _mm_cmplt_pd(hi[1][0][r], lo[1][1][r]));
      const __m128d above = _mm_and_pd(
          _mm_cmplt_pd(hi[0][1][r], lo[0][0][r]), _mm_cmplt_pd(hi[1][1][r], lo[1][0][r]));
      apart = _mm_or_pd(apart, _mm_or_pd(below, above));
    }
    return _mm_movemask_pd(apart) != 0;
  };
  const bool on_axes = apart_on.template operator()<2>([&](const double* p, __m128d* v) {
    v[0] = _mm_loadu_pd(p);
    v[1] = _mm_load1_pd(p + 2);
    zeros = _mm_add_pd(zeros, _mm_add_pd(_mm_sub_pd(v[0], v[0]), _mm_sub_pd(v[1], v[1])));
  });
  if (_mm_movemask_pd(_mm_cmpeq_pd(zeros, _mm_setzero_pd())) != 3) return false;
  if (on_axes) return true;
  return apart_on.template operator()<3>([&](const double* p, __m128d* v) {
    const __m128d xy = _mm_loadu_pd(p);
    const __m128d yz = _mm_loadu_pd(p + 1);
    v[0] = _mm_add_pd(xy, yz);
    v[1] = _mm_sub_pd(xy, yz);
    v[2] = _mm_add_pd(_mm_load1_pd(p + 2), _mm_xor_pd(_mm_load1_pd(p), negate_high));
  });
#else
  constexpr double kMax = std::numeric_limits<double>::max();
  bool finite = true;
  for (std::size_t i = 0; i < 4; ++i) {
    finite = finite && t0[i]->cwiseAbs().maxCoeff() <= kMax && t1[i]->cwiseAbs().maxCoeff() <= kMax;
  }
  if (!finite) return false;
  return ends_apart_on<NA>(
             t0,
             t1,
             [](const Eigen::Vector3d& p) {
               return std::array<double, 3>{p[0], p[1], p[2]};
             }) ||
         ends_apart_on<NA>(
             t0,
             t1,
             [](const Eigen::Vector3d& p) {
               return std::array<double, 3>{p[0] + p[1], p[1] + p[2], p[2] + p[0]};
             }) ||
         ends_apart_on<NA>(t0, t1, [](const Eigen::Vector3d& p) {
           return std::array<double, 3>{p[0] - p[1], p[1] - p[2], p[2] - p[0]};
         });
#endif
}

/// The pipeline's relative stage: ends_apart without a contact distance (half_width 0),
/// relative_boxes_apart with one.
template <std::size_t NA>
[[nodiscard]] bool relative_stage_apart(
    const std::array<const Eigen::Vector3d*, 4>& t0,
    const std::array<const Eigen::Vector3d*, 4>& t1,
    double half_width) {
  return half_width > 0.0 ? relative_boxes_apart_as<NA, true>(t0, t1, half_width)
                          : ends_apart<NA>(t0, t1);
}

}  // namespace skelcd::ccd::detail
