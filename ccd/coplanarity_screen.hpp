#pragma once
// The first decision of the conservative kernels (docs/ccd.md, "Conservative pipeline"), taken for
// four queries at once: the coplanarity cubic's coefficients with the screening error bound
// (detail/trilinear_cubic.hpp, trilinear_screen) certify one sign on all of [0,1], so the four
// points are never coplanar and the query has no contact. On a cloth step most queries end there
// (docs/benchmarks.md, "Where the cloth-ball step's kernel time goes"); screening them four to a
// vector, read straight from the position arrays, spares each the query's assembly and the call,
// and the queries it leaves go on from the kernel's next stage with the cubic it computed.

#include <array>
#include <cstdint>
#include <span>

#include "ccd/ccd_types.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/vertex_face.hpp"

namespace skelcd::ccd {

/// Point indices of four queries of one kind, into row-major #V × 3 position arrays:
/// vertex-face (v, f0, f1, f2) as VertexFaceQuery's v, f0, f1, f2; edge-edge (ea0, ea1, eb0, eb1)
/// as EdgeEdgeQuery's.
using ScreenQuads = std::span<const std::array<std::int32_t, 4>, 4>;

/// The coplanarity screens of four queries.
struct CoplanarityScreens {
  /// Bit k: the screen certifies query k's cubic one sign on [0,1] — the conservative kernel with
  /// min_separation 0 reports no contact for it (at this stage, or at the swept-AABB stage
  /// before it).
  unsigned apart = 0;
  /// Query k's coplanarity cubic in Bernstein form, the kernel's coefficients bit for bit.
  std::array<std::array<double, 4>, 4> coefficients{};
  /// Query k's largest |coordinate| of the cubic's difference vectors at both ends.
  std::array<double, 4> magnitude{};
};

/// The screens of four vertex-face queries, computed as vertex_face_ccd(query,
/// Accuracy::conservative, options) with options.min_separation == 0 computes its own, with the
/// same roundings in the same order. Uses AVX2 where the CPU has it, the baseline instruction set
/// otherwise, with the same results.
/// @param x_t0,x_t1 row-major #V × 3 positions (vertex v at x + 3 v) at the interval's two ends.
[[nodiscard]] CoplanarityScreens vertex_face_screen_x4(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

/// Four triangles' corners at one end: face k's f0, f1, f2, three doubles each.
using FaceCorners = std::array<std::array<const double*, 3>, 4>;

/// vertex_face_screen_x4 of one point moving from v_t0 to v_t1 (three doubles each) against four
/// faces given by their corners, without position arrays: the same differences, roundings and
/// results as the queries (v; face k) would have there.
[[nodiscard]] CoplanarityScreens point_faces_screen_x4(
    const double* v_t0, const double* v_t1, const FaceCorners& f_t0, const FaceCorners& f_t1);

/// vertex_face_screen_x4 for edge-edge queries (edge_edge_ccd).
[[nodiscard]] CoplanarityScreens edge_edge_screen_x4(
    const double* x_t0, const double* x_t1, ScreenQuads queries);

/// vertex_face_ccd(query, Accuracy::conservative, options), bit for bit, for a query whose
/// screen is lane `lane` of `screens` and did not certify it: the kernel from the stage after its
/// screen.
/// @pre options.min_separation == 0; `screens` from the query's own points, its bit `lane` of
///      apart clear; the swept AABBs of the query overlap (vertex_face_ccd_after_swept_aabbs:
///      that stage is skipped too).
[[nodiscard]] CcdResult vertex_face_ccd_after_screen(
    const VertexFaceQuery& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane);

/// vertex_face_ccd_after_screen for edge-edge queries (edge_edge_ccd).
[[nodiscard]] CcdResult edge_edge_ccd_after_screen(
    const EdgeEdgeQuery& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane);

}  // namespace skelcd::ccd
