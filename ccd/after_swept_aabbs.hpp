#pragma once
// The CCD queries for a caller that has already established what the first stage of the
// conservative pipeline tests (docs/ccd.md): that the swept AABBs of the two primitives overlap.
// A broad phase that filters feature pairs by their swept volumes (culling/candidates.hpp) has
// made that test, exactly, for every pair it hands over; the kernel repeating it was 6% of a bvh
// CCD interval.

#include "ccd/accuracy.hpp"
#include "ccd/ccd_types.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd {

/// vertex_face_ccd(query, accuracy, options), without the swept-AABB stage when it cannot reject:
/// `conservative` with min_separation == 0. Other accuracies and distances: vertex_face_ccd.
/// @pre the closed boxes of {v_t0, v_t1} and of the six corner positions overlap on every axis;
///      then the result is vertex_face_ccd's, bit for bit (that stage would have passed the query
///      on). Without the precondition the answer is still conservative: the stage only rejects.
[[nodiscard]] CcdResult vertex_face_ccd_after_swept_aabbs(
    const VertexFaceQuery& query, Accuracy accuracy, const CcdOptions& options);

/// edge_edge_ccd likewise: @pre the closed boxes of the two edges' four positions each overlap.
[[nodiscard]] CcdResult edge_edge_ccd_after_swept_aabbs(
    const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options);

}  // namespace skelcd::ccd
