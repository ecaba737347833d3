// Edge-edge CCD: the three accuracies behind one call.

#include "ccd/edge_edge.hpp"

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
    const EdgeEdgeQuery& q,
    const CcdOptions& options,
    CcdStats& stats,
    const detail::TrilinearScreen* known = nullptr) {
  // c(t) = (b0 - a0) . ((a1 - a0) x (b1 - b0)); n = d_a x d_b.
  const detail::DifferenceTriple t0{q.eb0_t0 - q.ea0_t0, q.ea1_t0 - q.ea0_t0, q.eb1_t0 - q.eb0_t0};
  const detail::DifferenceTriple t1{q.eb0_t1 - q.ea0_t1, q.ea1_t1 - q.ea0_t1, q.eb1_t1 - q.eb0_t1};
  // With w = b0 - a0: the segment parameters are u / nn and v / nn, nn = n . n, where
  // u = (w x d_b) . n, nn - u = ((a1 - b0) x d_b) . n,
  // v = (w x d_a) . n, nn - v = (d_a x (b1 - a0)) . n.
  const std::array<const Eigen::Vector3d*, 4> at_t0{&q.ea0_t0, &q.ea1_t0, &q.eb0_t0, &q.eb1_t0};
  const std::array<const Eigen::Vector3d*, 4> at_t1{&q.ea0_t1, &q.ea1_t1, &q.eb0_t1, &q.eb1_t1};
  const auto quartic_inputs = [&](detail::QuadrupleDifferences* g, double* lengths) {
    const int count = detail::inside_quadruples(detail::InsideQuartics::edge_edge, at_t0, at_t1, g);
    // Within s of contact: u, nn - u >= -s |n| |d_b|; v, nn - v >= -s |n| |d_a| (docs/ccd.md).
    if (lengths != nullptr) {
      lengths[0] = lengths[1] = detail::norm_bound(t0.z, t1.z);
      lengths[2] = lengths[3] = detail::norm_bound(t0.y, t1.y);
    }
    return count;
  };
  const auto quartics_x4 = [&](detail::QuarticLanes& g) {
    return detail::inside_quartic_lanes(detail::InsideQuartics::edge_edge, at_t0, at_t1, g);
  };
  // F(t, u, v) = (a0 + u (a1 - a0)) - (b0 + v (b1 - b0)) = (a0 - b0) + u (a1 - a0) + v (b0 - b1).
  const auto problem = [&] {
    detail::InclusionProblem p;
    p.d_t0 = q.ea0_t0 - q.eb0_t0;
    p.e_t0 = t0.y;
    p.g_t0 = q.eb0_t0 - q.eb1_t0;
    p.d_t1 = q.ea0_t1 - q.eb0_t1;
    p.e_t1 = t1.y;
    p.g_t1 = q.eb0_t1 - q.eb1_t1;
    p.triangle_domain = false;
    return p;
  };
  const auto relative_apart = [&] {
    return detail::relative_stage_apart<2>(at_t0, at_t1, 0.5 * options.min_separation);
  };
  return detail::conservative_pipeline(
      t0, t1, known, quartic_inputs, quartics_x4, problem, relative_apart, options, stats);
}

}  // namespace

CcdResult edge_edge_ccd(const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options) {
  CcdStats stats;
  return edge_edge_ccd(query, accuracy, options, stats);
}

CcdResult edge_edge_ccd(
    const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options, CcdStats& stats) {
  return detail::ccd_at_accuracy(
      query,
      accuracy,
      options,
      stats,
      conservative_after_aabbs,
      [](const EdgeEdgeQuery& q, const CcdOptions& o) {
        return edge_edge_ccd_exact(to_rational(q), o);
      },
      detail::edge_edge_ccd_fast);
}

CcdResult edge_edge_ccd_after_swept_aabbs(
    const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options) {
  return detail::ccd_after_swept_aabbs(
      query,
      accuracy,
      options,
      conservative_after_aabbs,
      [](const EdgeEdgeQuery& q, Accuracy a, const CcdOptions& o) {
        return edge_edge_ccd(q, a, o);
      });
}

CcdResult edge_edge_ccd_after_screen(
    const EdgeEdgeQuery& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane) {
  return detail::ccd_after_screen(query, options, screens, lane, conservative_after_aabbs);
}

}  // namespace skelcd::ccd
