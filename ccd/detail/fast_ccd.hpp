#pragma once
// The `fast` accuracy: plain double, no error control. Roots of the coplanarity cubic in [0,1],
// then an inside test at each root. Kept to show what accuracy costs: it misses contacts (coplanar
// motion, grazing contacts at edges and corners, roots lost to rounding).

#include "ccd/ccd_types.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd::detail {

[[nodiscard]] CcdResult vertex_face_ccd_fast(const VertexFaceQuery& query);
[[nodiscard]] CcdResult edge_edge_ccd_fast(const EdgeEdgeQuery& query);

}  // namespace skelcd::ccd::detail
