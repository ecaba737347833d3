// Vertex-face CCD: the three accuracies behind one call.

#include "ccd/vertex_face.hpp"

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/entry_points.hpp"
#include "ccd/detail/fast_ccd.hpp"
#include "ccd/detail/relative_boxes.hpp"
#include "ccd/exact_ccd.hpp"

namespace skelcd::ccd {
namespace {

// conservative, once the swept AABBs are known to overlap: the pipeline of
// detail/conservative_pipeline.hpp. `known`: the query's coplanarity screen, already computed
// and not certified (the pipeline then goes on from its next stage), or null.
CcdResult conservative_after_aabbs(
    const VertexFaceQuery& q,
    const CcdOptions& options,
    CcdStats& stats,
    const detail::TrilinearScreen* known = nullptr) {
  // c(t) = (p - a) . ((b - a) x (c - a)).
  const detail::DifferenceTriple t0{q.v_t0 - q.f0_t0, q.f1_t0 - q.f0_t0, q.f2_t0 - q.f0_t0};
  const detail::DifferenceTriple t1{q.v_t1 - q.f0_t1, q.f1_t1 - q.f0_t1, q.f2_t1 - q.f0_t1};
  // Inside conditions n . ((b - a) x (p - a)), n . ((c - b) x (p - b)), n . ((a - c) x (p - c)),
  // n = (b - a) x (c - a): each (A x B) . (C x D) of single differences.
  const std::array<const Eigen::Vector3d*, 4> at_t0{&q.v_t0, &q.f0_t0, &q.f1_t0, &q.f2_t0};
  const std::array<const Eigen::Vector3d*, 4> at_t1{&q.v_t1, &q.f0_t1, &q.f1_t1, &q.f2_t1};
  const auto quartic_inputs = [&](detail::QuadrupleDifferences* g, double* lengths) {
    const int count =
        detail::inside_quadruples(detail::InsideQuartics::vertex_face, at_t0, at_t1, g);
    // Within s of contact the inside conditions are >= -s |n| times the length of their edge
    // (b - a, c - b, a - c): the C factors of quadruples 1 and 2, y of quadruple 0.
    if (lengths != nullptr) {
      lengths[0] = detail::norm_bound(t0.y, t1.y);
      lengths[1] = detail::norm_bound(g[1].c_t0, g[1].c_t1);
      lengths[2] = detail::norm_bound(g[2].c_t0, g[2].c_t1);
    }
    return count;
  };
  const auto quartics_x4 = [&](detail::QuarticLanes& g) {
    return detail::inside_quartic_lanes(detail::InsideQuartics::vertex_face, at_t0, at_t1, g);
  };
  // F(t, u, v) = p - (a + u (b - a) + v (c - a)) = (p - a) + u (a - b) + v (a - c).
  const auto problem = [&] {
    detail::InclusionProblem p;
    p.d_t0 = t0.x;
    p.e_t0 = q.f0_t0 - q.f1_t0;
    p.g_t0 = q.f0_t0 - q.f2_t0;
    p.d_t1 = t1.x;
    p.e_t1 = q.f0_t1 - q.f1_t1;
    p.g_t1 = q.f0_t1 - q.f2_t1;
    p.triangle_domain = true;
    return p;
  };
  const auto relative_apart = [&] {
    return detail::relative_stage_apart<1>(at_t0, at_t1, 0.5 * options.min_separation);
  };
  return detail::conservative_pipeline(
      t0, t1, known, quartic_inputs, quartics_x4, problem, relative_apart, options, stats);
}

}  // namespace

CcdResult vertex_face_ccd(
    const VertexFaceQuery& query, Accuracy accuracy, const CcdOptions& options) {
  CcdStats stats;
  return vertex_face_ccd(query, accuracy, options, stats);
}

CcdResult vertex_face_ccd(
    const VertexFaceQuery& query, Accuracy accuracy, const CcdOptions& options, CcdStats& stats) {
  return detail::ccd_at_accuracy(
      query,
      accuracy,
      options,
      stats,
      conservative_after_aabbs,
      [](const VertexFaceQuery& q, const CcdOptions& o) {
        return vertex_face_ccd_exact(to_rational(q), o);
      },
      detail::vertex_face_ccd_fast);
}

CcdResult vertex_face_ccd_after_swept_aabbs(
    const VertexFaceQuery& query, Accuracy accuracy, const CcdOptions& options) {
  return detail::ccd_after_swept_aabbs(
      query,
      accuracy,
      options,
      conservative_after_aabbs,
      [](const VertexFaceQuery& q, Accuracy a, const CcdOptions& o) {
        return vertex_face_ccd(q, a, o);
      });
}

CcdResult vertex_face_ccd_after_screen(
    const VertexFaceQuery& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane) {
  return detail::ccd_after_screen(query, options, screens, lane, conservative_after_aabbs);
}

}  // namespace skelcd::ccd
