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
/// a is corner j of b (the same mesh vertex), -1 otherwise. A degenerate a may repeat a vertex
/// and so name one corner of b twice or three times; the shared part is the hull of the distinct
/// corners named — {1, 1, -1} shares b's corner 1 alone, {1, 1, 2} the edge (1, 2).
using SharedCorners = std::array<std::int8_t, 3>;
inline constexpr SharedCorners kNoSharedCorners{-1, -1, -1};

/// True iff the closed triangles have a common point — beyond their shared vertex or edge when
/// they share one (two triangles meeting only at a shared vertex or along a shared edge do not
/// intersect). Exact for every input, including coplanar and degenerate triangles.
[[nodiscard]] bool triangles_intersect(
    const TriangleTriangleQuery& query,
    const SharedCorners& shared_with_b = kNoSharedCorners);

/// What triangles_intersect computes of one triangle (p0, p1, p2) before anything else: its
/// normal (p1 - p0) x (p2 - p0) in doubles and each component's permanent, which filter the
/// triangle's degeneracy and the side of every point against its plane. A DCD computes it once
/// per triangle and instant instead of once per tested pair.
struct TrianglePlane {
  double n[3];
  double m[3];
};

/// The plane data of (p0, p1, p2), in that corner order.
[[nodiscard]] TrianglePlane triangle_plane(
    const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, const Eigen::Vector3d& p2);

/// triangles_intersect(query, shared_with_b), the same answer for every input, with the planes
/// given instead of computed.
/// @pre plane_a == triangle_plane(query.a0, query.a1, query.a2), plane_b likewise for b.
[[nodiscard]] bool triangles_intersect_with_planes(
    const TriangleTriangleQuery& query,
    const SharedCorners& shared_with_b,
    const TrianglePlane& plane_a,
    const TrianglePlane& plane_b);

/// The first step of the test of a pair without shared corners, for a caller that gathers its
/// pairs' corners itself (the DCD): the sides of a's corners against b's plane by the static
/// filter alone. About half of a real mesh's tested pairs stop here, before their six corners are
/// copied into a query.
struct FirstSides {
  int o[3];            ///< orient3d(b0, b1, b2, a_i) where decided
  unsigned undecided;  ///< bit i set: o[i] left to the exact predicate
};

/// True when the filter proves a's corners (a_i: three coordinates each) strictly on one side of
/// b's plane: the closed triangles do not meet, as triangles_intersect would answer. Otherwise
/// `out` holds what it decided, for triangles_intersect_after_first_sides.
/// @pre plane_b == triangle_plane(b0, b1, b2); b0: b's first corner.
[[nodiscard]] bool first_sides_separate(
    const double* a0,
    const double* a1,
    const double* a2,
    const double* b0,
    const TrianglePlane& plane_b,
    FirstSides& out);

/// triangles_intersect(query) for a pair without shared corners whose first_sides_separate was
/// false, finishing from `first` (the same answer for every input).
/// @pre the planes as for triangles_intersect_with_planes; `first` from first_sides_separate on
/// the query's corners and plane_b.
[[nodiscard]] bool triangles_intersect_after_first_sides(
    const TriangleTriangleQuery& query,
    const TrianglePlane& plane_a,
    const TrianglePlane& plane_b,
    const FirstSides& first);

}  // namespace skelcd::ccd
