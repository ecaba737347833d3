#pragma once
// The product's CCD kernels under other names. The culling stages give the kernels themselves
// what only they stand for — pairs settled by certified vertex fans (ccd_uses_fans), the
// four-query coplanarity screen (run_ccd_tests) — and a test passes these to see every feature
// pair reach a kernel call, with the kernels' own answers.

#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::test {

inline ccd::CcdResult renamed_vertex_face_ccd(
    const ccd::VertexFaceQuery& q, ccd::Accuracy accuracy, const ccd::CcdOptions& options) {
  return ccd::vertex_face_ccd(q, accuracy, options);
}

inline ccd::CcdResult renamed_edge_edge_ccd(
    const ccd::EdgeEdgeQuery& q, ccd::Accuracy accuracy, const ccd::CcdOptions& options) {
  return ccd::edge_edge_ccd(q, accuracy, options);
}

}  // namespace skelcd::test
