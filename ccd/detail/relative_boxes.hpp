#pragma once
// The relative-box stage of the conservative pipeline (docs/ccd.md, "Relative boxes"): the query's
// points minus one common motion. Subtracting t·u from every point of a vertex-face or edge-edge
// query changes no distance between them at any instant t, and a point moving linearly from p₀ to
// p₁ moves, less t·u, inside the box of p₀ and p₁ − u. So when the boxes of the two features'
// relative ends, each grown by half of min_separation, are apart on some axis, the features never
// come within min_separation of each other over [0, 1]. Any u is sound; u is the mean displacement
// of the query's four points. With a contact distance each p₁ − u is bracketed by the doubles
// around its rounded value (round-to-nearest is within half an ulp), so the boxes hold the exact
// relative ends. Without one the boxes need not hold them: every end compared is an input
// coordinate or fl(p₁ − u) with the query's one u, and rounding is monotone (fl(x − u) < fl(y − u)
// implies x < y, fl(x − u) < c implies x − u < c for a double c, and the same the other way), so a
// strict gap between the rounded ends is a gap between the exact ones.

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "ccd/detail/float_bounds.hpp"

namespace skelcd::ccd::detail {

/// relative_boxes_apart with (kWidth: half_width > 0) or without a contact distance.
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

}  // namespace skelcd::ccd::detail
