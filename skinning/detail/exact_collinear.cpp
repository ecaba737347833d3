#include "skinning/detail/exact_collinear.hpp"

#include <cassert>
#include <cmath>
#include <limits>

#include <gmpxx.h>

namespace skelcd::skinning::detail {
namespace {

// The triangle has zero area iff its projections on the three coordinate planes all do: the
// components of (b − a) × (c − a) are exactly the 2D orientation determinants of those
// projections. Each determinant is first evaluated in floating point; Shewchuk's bound
// (Adaptive Precision Floating-Point Arithmetic, 1997, orient2d stage A) certifies "non-zero".
constexpr double kEpsilon = std::numeric_limits<double>::epsilon() / 2;  // unit round-off 2^-53
constexpr double kOrient2dBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;
// Below this magnitude a product may have lost bits to gradual underflow, which the bound above
// does not cover; such determinants go to the exact path.
constexpr double kUnderflowGuard = std::numeric_limits<double>::min() / kEpsilon;

enum class Sign { zero, nonzero, unknown };

/// Orientation determinant of (a, b, c) projected on coordinates (i, j), filtered.
Sign filtered_orient2d(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    int i,
    int j) {
  const double left = (a[i] - c[i]) * (b[j] - c[j]);
  const double right = (a[j] - c[j]) * (b[i] - c[i]);
  const double det = left - right;
  const double sum = std::abs(left) + std::abs(right);
  if (sum == 0.0) {
    // Both products are zero: each has a zero factor (a difference of doubles is zero only when
    // the doubles are equal) or underflowed. Only the first case is certain.
    const bool exact_zero = ((a[i] == c[i]) || (b[j] == c[j])) && ((a[j] == c[j]) || (b[i] == c[i]));
    return exact_zero ? Sign::zero : Sign::unknown;
  }
  if (sum < kUnderflowGuard) return Sign::unknown;
  if (std::abs(det) > kOrient2dBound * sum) return Sign::nonzero;
  return Sign::unknown;
}

bool exact_orient2d_is_zero(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    int i,
    int j) {
  const mpq_class ai(a[i]), aj(a[j]), bi(b[i]), bj(b[j]), ci(c[i]), cj(c[j]);
  const mpq_class det = (ai - ci) * (bj - cj) - (aj - cj) * (bi - ci);
  return sgn(det) == 0;
}

}  // namespace

bool exactly_collinear(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c) {
  assert(a.allFinite() && b.allFinite() && c.allFinite());
  constexpr int kPlanes[3][2] = {{0, 1}, {1, 2}, {2, 0}};
  bool unknown[3] = {false, false, false};
  // Filter first on every plane: one certified non-zero projection settles it.
  for (int p = 0; p < 3; ++p) {
    const Sign s = filtered_orient2d(a, b, c, kPlanes[p][0], kPlanes[p][1]);
    if (s == Sign::nonzero) return false;
    unknown[p] = (s == Sign::unknown);
  }
  for (int p = 0; p < 3; ++p) {
    if (unknown[p] && !exact_orient2d_is_zero(a, b, c, kPlanes[p][0], kPlanes[p][1])) return false;
  }
  return true;
}

}  // namespace skelcd::skinning::detail
