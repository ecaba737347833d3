#pragma once
// Exact test of whether three points in space are collinear (the triangle they span has zero area).
// Used by the topology to report degenerate triangles without an epsilon.

#include <Eigen/Core>

namespace skelcd::skinning::detail {

/// True when a, b and c lie exactly on one line (including coincident points), decided on the
/// exact double values: (b − a) × (c − a) = 0 exactly.
/// A floating-point filter with Shewchuk's orient2d error bound settles almost every triangle;
/// the rest fall back to GMP rationals, which represent every double exactly.
/// @pre the coordinates are finite.
[[nodiscard]] bool exactly_collinear(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c);

}  // namespace skelcd::skinning::detail
