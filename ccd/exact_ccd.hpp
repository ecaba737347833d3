#pragma once
// The exact rational reference for vertex-face and edge-edge CCD: GMP rationals on the exact input
// values, no rounding anywhere. It is the judge in tests and the `exact` accuracy of
// vertex_face_ccd / edge_edge_ccd; it also accepts inputs that are not doubles (for example the
// decimal 0.1 read as exactly 1/10 by `skelcd ccd-queries`). The algorithm and why it is exact are
// in docs/ccd.md ("The exact reference").

#include <array>

#include <gmpxx.h>

#include "ccd/ccd_types.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd {

/// A point with exact rational coordinates.
using RationalPoint = std::array<mpq_class, 3>;

/// As VertexFaceQuery, with rational coordinates.
struct RationalVertexFaceQuery {
  RationalPoint v_t0, f0_t0, f1_t0, f2_t0;  ///< vertex and triangle corners at t = 0
  RationalPoint v_t1, f0_t1, f1_t1, f2_t1;  ///< the same points at t = 1
};

/// As EdgeEdgeQuery, with rational coordinates.
struct RationalEdgeEdgeQuery {
  RationalPoint ea0_t0, ea1_t0, eb0_t0, eb1_t0;  ///< edge a and edge b endpoints at t = 0
  RationalPoint ea0_t1, ea1_t1, eb0_t1, eb1_t1;  ///< the same points at t = 1
};

/// The exact rational value of every coordinate (every finite double is a rational).
[[nodiscard]] RationalVertexFaceQuery to_rational(const VertexFaceQuery& query);
[[nodiscard]] RationalEdgeEdgeQuery to_rational(const EdgeEdgeQuery& query);

/// Exact answer with the first contact time bracketed by rationals.
struct ExactCcdResult {
  bool hit = false;
  /// When hit: the earliest contact time t* satisfies toi_lo <= t* <= toi_hi (equal when t* is
  /// rational and was found exactly). Both 1 when !hit.
  mpq_class toi_lo = 1;
  mpq_class toi_hi = 1;
};

/// Does the vertex touch the closed triangle at some t in [0,1]? Exact: hit iff they touch.
/// @param toi_width the time-of-impact bracket is narrowed to at most this width (unitless, > 0).
/// @note Contact only (min_separation 0); allocates (GMP).
[[nodiscard]] ExactCcdResult vertex_face_ccd_rational(
    const RationalVertexFaceQuery& query,
    const mpq_class& toi_width = mpq_class(1, 1'000'000));

/// Do the two closed segments touch at some t in [0,1]? Exact: hit iff they touch.
[[nodiscard]] ExactCcdResult edge_edge_ccd_rational(
    const RationalEdgeEdgeQuery& query,
    const mpq_class& toi_width = mpq_class(1, 1'000'000));

/// The exact result as a CcdResult: [toi_lower, toi_upper] is the rational bracket rounded outward
/// to doubles and narrowed to options.toi_tolerance. @pre options.min_separation == 0
[[nodiscard]] CcdResult vertex_face_ccd_exact(
    const RationalVertexFaceQuery& query,
    const CcdOptions& options = {});
[[nodiscard]] CcdResult edge_edge_ccd_exact(
    const RationalEdgeEdgeQuery& query,
    const CcdOptions& options = {});

/// Largest double <= q and smallest double >= q (q finite, within the double range).
[[nodiscard]] double round_down(const mpq_class& q);
[[nodiscard]] double round_up(const mpq_class& q);
/// The double nearest to q (ties to even), as IEEE round-to-nearest would give; +-infinity when
/// q is beyond the largest finite double by more than half an ulp.
[[nodiscard]] double round_to_nearest(const mpq_class& q);

}  // namespace skelcd::ccd
