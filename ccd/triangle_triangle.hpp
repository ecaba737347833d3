#pragma once
// Triangle-triangle intersection at an instant (DCD), exact: filtered floating-point orientation
// predicates with an exact rational fallback.

#include <array>
#include <cstdint>

#include <Eigen/Core>

namespace skelcd::ccd {

struct TriangleTriangleQuery {
  Eigen::Vector3d a0, a1, a2;  ///< triangle a
  Eigen::Vector3d b0, b1, b2;  ///< triangle b
};

/// Which corners the two triangles share as mesh vertices: shared_with_b[i] = j when corner i of
/// a is corner j of b (the same mesh vertex), -1 otherwise.
using SharedCorners = std::array<std::int8_t, 3>;
inline constexpr SharedCorners kNoSharedCorners{-1, -1, -1};

/// True iff the closed triangles have a common point — beyond their shared vertex or edge when
/// they share one (two triangles meeting only at a shared vertex or along a shared edge do not
/// intersect). Exact for every input, including coplanar and degenerate triangles.
[[nodiscard]] bool triangles_intersect(
    const TriangleTriangleQuery& query,
    const SharedCorners& shared_with_b = kNoSharedCorners);

}  // namespace skelcd::ccd
