// Edge-edge CCD: the three accuracies behind one call.

#include "ccd/edge_edge.hpp"

#include <cassert>

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/coplanarity_screen.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/fast_ccd.hpp"
#include "ccd/detail/relative_boxes.hpp"
#include "ccd/detail/screen_x4.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/filters.hpp"

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
  // u = (w x d_b) . n, nn - u = ((a1 - b0) x d_b) . n, v = (w x d_a) . n, nn - v = (d_a x (b1 - a0)) . n.
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

// conservative: swept AABBs, then the rest of the pipeline.
CcdResult conservative(const EdgeEdgeQuery& q, const CcdOptions& options, CcdStats& stats) {
  if (swept_aabbs_disjoint(q, options.min_separation)) {
    ++stats.aabb_rejected;
    return {};
  }
  return conservative_after_aabbs(q, options, stats);
}

}  // namespace

CcdResult edge_edge_ccd(const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options) {
  CcdStats stats;
  return edge_edge_ccd(query, accuracy, options, stats);
}

CcdResult edge_edge_ccd(const EdgeEdgeQuery& query,
                        Accuracy accuracy,
                        const CcdOptions& options,
                        CcdStats& stats) {
  assert(options.min_separation >= 0.0);
  CcdResult r;
  switch (accuracy) {
    case Accuracy::exact:
      r = swept_aabbs_disjoint(query, 0.0) ? CcdResult{} : edge_edge_ccd_exact(to_rational(query), options);
      break;
    case Accuracy::conservative:
      r = conservative(query, options, stats);
      break;
    case Accuracy::fast:
      r = detail::edge_edge_ccd_fast(query);
      break;
  }
  ++stats.queries;
  if (r.hit) ++stats.hits;
  return r;
}

CcdResult edge_edge_ccd_after_swept_aabbs(
    const EdgeEdgeQuery& query, Accuracy accuracy, const CcdOptions& options) {
  // With min_separation 0 the swept-AABB stage rejects exactly the queries whose boxes are
  // disjoint (fl(x - y) > 0 iff x > y), which the precondition rules out: skip it.
  if (accuracy != Accuracy::conservative || options.min_separation != 0.0) {
    return edge_edge_ccd(query, accuracy, options);
  }
  CcdStats stats;
  return conservative_after_aabbs(query, options, stats);
}

CcdResult edge_edge_ccd_after_screen(
    const EdgeEdgeQuery& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane) {
  assert(options.min_separation == 0.0 && (screens.apart >> lane & 1u) == 0);
  const detail::TrilinearScreen known = detail::lane_screen(screens, lane);
  CcdStats stats;
  return conservative_after_aabbs(query, options, stats, &known);
}

}  // namespace skelcd::ccd
