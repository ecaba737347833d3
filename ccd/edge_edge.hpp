#pragma once
// Edge-edge continuous collision query: do two segments touch for some t in [0,1] when every
// endpoint moves linearly from its _t0 to its _t1 position?

#include <Eigen/Core>

#include "ccd/accuracy.hpp"
#include "ccd/ccd_types.hpp"

namespace skelcd::ccd {

struct EdgeEdgeQuery {
  Eigen::Vector3d ea0_t0, ea1_t0, eb0_t0, eb1_t0;  ///< edge a and edge b endpoints at t = 0
  Eigen::Vector3d ea0_t1, ea1_t1, eb0_t1, eb1_t1;  ///< the same points at t = 1
};

/// Earliest contact of the two closed segments over the closed interval [0,1]; guarantees as
/// for vertex_face_ccd.
[[nodiscard]] CcdResult edge_edge_ccd(
    const EdgeEdgeQuery& query,
    Accuracy accuracy = Accuracy::conservative,
    const CcdOptions& options = {});

/// As above, and adds to `stats` what each stage of the pipeline removed.
[[nodiscard]] CcdResult edge_edge_ccd(
    const EdgeEdgeQuery& query,
    Accuracy accuracy,
    const CcdOptions& options,
    CcdStats& stats);

}  // namespace skelcd::ccd
