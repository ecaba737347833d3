#pragma once
// Exact orientation of four points: filtered double with a proven dynamic error bound, GMP rational
// fallback when the filter cannot decide (ccd/detail/filtered.hpp, docs/ccd.md).

#include <Eigen/Core>

namespace skelcd::ccd {

/// Sign of det(b - a, c - a, d - a): +1 when d is on the side of the plane (a, b, c) its normal
/// (b - a) x (c - a) points to, -1 on the other side, 0 when the four points are coplanar (or a, b, c
/// are collinear). Exact for every finite input.
[[nodiscard]] int orient3d(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d);

}  // namespace skelcd::ccd
