#pragma once
// What vertex_face.cpp and edge_edge.cpp do alike around their own conservative pipeline: the
// choice between the three accuracies, the entry for a caller that has tested the swept AABBs,
// and the entry after the four-lane coplanarity screen. Each query kind supplies its pieces:
// `after_aabbs(query, options, stats, known)`, the conservative pipeline once the swept AABBs
// overlap (`known`: the query's coplanarity screen, computed and not certified, or null);
// `exact(query, options)` and `fast(query)`, the other two accuracies.

#include <cassert>

#include "ccd/accuracy.hpp"
#include "ccd/ccd_types.hpp"
#include "ccd/coplanarity_screen.hpp"
#include "ccd/detail/screen_x4.hpp"
#include "ccd/filters.hpp"

namespace skelcd::ccd::detail {

/// vertex_face_ccd / edge_edge_ccd: the query at `accuracy`, its stages counted in `stats`.
template <class Query, class AfterAabbs, class Exact, class Fast>
CcdResult ccd_at_accuracy(
    const Query& query,
    Accuracy accuracy,
    const CcdOptions& options,
    CcdStats& stats,
    const AfterAabbs& after_aabbs,
    const Exact& exact,
    const Fast& fast) {
  assert(options.min_separation >= 0.0);
  CcdResult r;
  switch (accuracy) {
    case Accuracy::exact:
      // The swept-box test is exact in double and saves the rational conversion.
      r = swept_aabbs_disjoint(query, 0.0) ? CcdResult{} : exact(query, options);
      break;
    case Accuracy::conservative:
      // The pipeline's first stage, then the rest of it.
      if (swept_aabbs_disjoint(query, options.min_separation)) {
        ++stats.aabb_rejected;
      } else {
        r = after_aabbs(query, options, stats, nullptr);
      }
      break;
    case Accuracy::fast:
      r = fast(query);
      break;
  }
  ++stats.queries;
  if (r.hit) ++stats.hits;
  return r;
}

/// *_ccd_after_swept_aabbs (after_swept_aabbs.hpp): `at_accuracy(query, accuracy, options)`
/// unless the swept-AABB stage cannot reject, the conservative pipeline from its next stage then.
template <class Query, class AfterAabbs, class AtAccuracy>
CcdResult ccd_after_swept_aabbs(
    const Query& query,
    Accuracy accuracy,
    const CcdOptions& options,
    const AfterAabbs& after_aabbs,
    const AtAccuracy& at_accuracy) {
  // With min_separation 0 the swept-AABB stage rejects exactly the queries whose boxes are
  // disjoint (fl(x - y) > 0 iff x > y), which the precondition rules out: skip it.
  if (accuracy != Accuracy::conservative || options.min_separation != 0.0) {
    return at_accuracy(query, accuracy, options);
  }
  CcdStats stats;
  return after_aabbs(query, options, stats, nullptr);
}

/// *_ccd_after_screen (coplanarity_screen.hpp): the pipeline after lane `lane` of the four-lane
/// screen, which neither set apart nor certified.
template <class Query, class AfterAabbs>
CcdResult ccd_after_screen(
    const Query& query,
    const CcdOptions& options,
    const CoplanarityScreens& screens,
    int lane,
    const AfterAabbs& after_aabbs) {
  assert(options.min_separation == 0.0 && (screens.apart >> lane & 1u) == 0);
  const TrilinearScreen known = lane_screen(screens, lane);
  CcdStats stats;
  return after_aabbs(query, options, stats, &known);
}

}  // namespace skelcd::ccd::detail
