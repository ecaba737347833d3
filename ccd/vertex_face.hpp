#pragma once
// Vertex-face continuous collision query: does a vertex touch a triangle for some t in [0,1] when
// every point moves linearly from its _t0 to its _t1 position?

#include <Eigen/Core>

#include "ccd/accuracy.hpp"
#include "ccd/ccd_types.hpp"

namespace skelcd::ccd {

struct VertexFaceQuery {
  Eigen::Vector3d v_t0, f0_t0, f1_t0, f2_t0;  ///< vertex and triangle corners at t = 0
  Eigen::Vector3d v_t1, f0_t1, f1_t1, f2_t1;  ///< the same points at t = 1
};

/// Earliest contact of the vertex with the closed triangle over the closed interval [0,1].
/// Guarantee by accuracy: `exact` — hit iff they touch; `conservative` — hit == false implies they
/// do not touch (nor come within min_separation), see docs/ccd.md for the error bound;
/// `fast` — no guarantee (and min_separation is ignored).
/// `hit == true` (conservative) implies that at some time in [toi_lower, toi_upper] the vertex came
/// within sqrt(3) (min_separation + relative_distance_tolerance * extent + 2 err) of the triangle
/// (err: the rounding bound of docs/ccd.md), unless status == iteration_limit; in every case
/// toi_lower <= the true first contact time.
/// @pre finite coordinates (conservative answers hit for non-finite input); exact: min_separation == 0.
/// @note Kernel: never throws, never allocates (except `exact`, which uses GMP).
[[nodiscard]] CcdResult vertex_face_ccd(
    const VertexFaceQuery& query,
    Accuracy accuracy = Accuracy::conservative,
    const CcdOptions& options = {});

/// As above, and adds to `stats` what each stage of the pipeline removed.
[[nodiscard]] CcdResult vertex_face_ccd(
    const VertexFaceQuery& query,
    Accuracy accuracy,
    const CcdOptions& options,
    CcdStats& stats);

}  // namespace skelcd::ccd
