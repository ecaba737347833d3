#pragma once
// The orient3d sign predicate: floating-point filter with an exact (GMP rational) fallback.
// Stand-in for ccd/'s exact-sign predicates while those are being written; same contract.

#include <Eigen/Core>

namespace skelcd::segmentation::detail {

/// Exact sign of (a − d) · ((b − a) × (c − a)) = det[a − d; b − d; c − d]: +1 when d sees the
/// triangle abc from its back (abc counter-clockwise seen from the side opposite d), −1 when
/// from its front, 0 when the four points are coplanar (or abc is degenerate).
/// @note Filtered with Shewchuk's static bound (7 + 56ε)ε · permanent; only when the filter
///   cannot decide is the determinant evaluated exactly on the input doubles.
[[nodiscard]] int orient3d_sign(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d);

/// The same sign, always in exact rational arithmetic (the reference for tests).
[[nodiscard]] int orient3d_sign_exact(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d);

}  // namespace skelcd::segmentation::detail
