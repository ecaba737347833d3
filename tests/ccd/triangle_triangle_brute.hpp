#pragma once
// An independent brute-force rational reference for triangle-triangle intersection: A n B is the
// set of points sum alpha_i a_i = sum beta_j b_j with alpha, beta >= 0 summing to 1 — a polytope
// whose vertices are the basic feasible solutions of that linear system. Enumerating every basic
// solution exactly (GMP) gives every extreme point of A n B; the triangles meet beyond their
// shared part iff one of those points is outside it. Slow (tens of microseconds): tests only.

#include "ccd/triangle_triangle.hpp"

namespace skelcd::ccd::test {

/// What ccd::triangles_intersect must answer, computed independently and exactly.
[[nodiscard]] bool brute_intersect(const TriangleTriangleQuery& q, const SharedCorners& shared);

}  // namespace skelcd::ccd::test
