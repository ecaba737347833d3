#pragma once
// The triangle-triangle test as it was before the static-filter rewrite (issue 14), kept as the
// reference that ccd::triangles_intersect must agree with on every input.

#include "ccd/triangle_triangle.hpp"

namespace skelcd::ccd::reference {

/// ccd::triangles_intersect at 5b0653f, verbatim: same arguments, same answer for every input.
[[nodiscard]] bool triangles_intersect_reference(
    const TriangleTriangleQuery& query, const SharedCorners& shared_with_b = kNoSharedCorners);

}  // namespace skelcd::ccd::reference
