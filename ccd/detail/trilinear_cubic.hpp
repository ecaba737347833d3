#pragma once
// The cubic det(X(t), Y(t), Z(t)) of three linearly moving difference vectors, in Bernstein form with
// a rounding-error bound, and a bound on |Y(t) x Z(t)|. Shared by the public orientation cubic
// (polynomial_sign.hpp) and the CCD coplanarity filter (filters.cpp). Derivation: docs/ccd.md.

#include <Eigen/Core>

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

/// N >= |Y(t) x Z(t)| for all t in [0,1], rounding included.
[[nodiscard]] double cross_norm_bound(const DifferenceTriple& t0, const DifferenceTriple& t1);

}  // namespace skelcd::ccd::detail
