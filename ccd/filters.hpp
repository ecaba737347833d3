#pragma once
// Cheap certified rejection tests for CCD queries, run before the conservative solver and usable
// on their own by culling. Each answers "proven separated over [0,1]" (true) or "don't know"
// (false); a true is never wrong for finite input. Counters of how many queries each stage removed
// are in CcdStats (ccd_types.hpp).

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd {

/// Swept-AABB rejection: a linearly moving point stays inside the box of its two positions, so if
/// the boxes swept by the two primitives over [0,1] are more than `min_separation` apart along an
/// axis, they never come within min_separation. Exact (double comparisons and a monotone subtraction).
/// @param min_separation distance in coordinate units, >= 0.
[[nodiscard]] bool swept_aabbs_disjoint(const VertexFaceQuery& query, double min_separation = 0.0);
[[nodiscard]] bool swept_aabbs_disjoint(const EdgeEdgeQuery& query, double min_separation = 0.0);

/// Deforming non-penetration filter (Tang, Manocha, Tong 2010): contact needs the four points to be
/// coplanar, i.e. the cubic c(t) = (p - a) . n(t) (vertex-face, n = (b - a) x (c - a)) or
/// (b0 - a0) . (d_a x d_b) (edge-edge) to vanish, and contact within distance s needs
/// |c(t)| <= s |n(t)|. True when the Bernstein coefficients of c, with the rounding bound of
/// docs/ccd.md and the margin s * max|n|, prove |c(t)| > s |n(t)| on all of [0,1].
[[nodiscard]] bool coplanarity_filter_rejects(const VertexFaceQuery& query, double min_separation = 0.0);
[[nodiscard]] bool coplanarity_filter_rejects(const EdgeEdgeQuery& query, double min_separation = 0.0);

}  // namespace skelcd::ccd
