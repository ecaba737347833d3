#pragma once
// The conservative CCD pipeline shared by vertex-face and edge-edge, after the swept-AABB test
// (docs/ccd.md, "Conservative pipeline"):
//   1. coplanarity filter — the cubic c(t) (with min_separation: |c| > s |n|) certified away from 0;
//   2. algebraic filter — certified decisions on intervals (with min_separation: widened by it);
//   3. inclusion solver — whatever is left, from the first time the filters could not exclude.

#include <algorithm>
#include <cmath>

#include "ccd/ccd_types.hpp"
#include "ccd/detail/algebraic_filter.hpp"
#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/inclusion_solver.hpp"
#include "ccd/detail/trilinear_cubic.hpp"

namespace skelcd::ccd::detail {

// Levels of de Casteljau halving the coplanarity filter may spend before giving up.
inline constexpr int kCoplanaritySubdivisions = 2;

/// Upper bound on |x(t)| over [0,1] for x linear in t (convexity: the larger end), rounded up.
inline double norm_bound(const Eigen::Vector3d& x_t0, const Eigen::Vector3d& x_t1) {
  const double m = std::max(x_t0.squaredNorm(), x_t1.squaredNorm());
  return std::sqrt(m * kRoundUp) * kRoundUp;
}

/// @param coplanarity_t0/_t1 X, Y, Z with c(t) = X . (Y x Z) and n = Y x Z.
/// @param make_quartics fills arrays of BernsteinQuartic and of edge-length bounds L_i and returns
/// how many (<= 4): at a point within distance s of contact, g_i >= -s |n| L_i (docs/ccd.md).
template <typename MakeQuartics>
CcdResult conservative_pipeline(const DifferenceTriple& coplanarity_t0,
                                const DifferenceTriple& coplanarity_t1,
                                MakeQuartics&& make_quartics,
                                InclusionProblem& problem,
                                const CcdOptions& options,
                                CcdStats& stats) {
  const double s = options.min_separation;
  BernsteinCubic c = trilinear_determinant(coplanarity_t0, coplanarity_t1);
  double normal_bound = 0.0;
  if (s > 0.0) {
    // |c(t)| <= s |n(t)| <= s N at any time within s: widen the error by s N (docs/ccd.md).
    normal_bound = cross_norm_bound(coplanarity_t0, coplanarity_t1);
    c.error = add_up(c.error, s * normal_bound * kRoundUp);
  }
  if (cubic_sign(c, kCoplanaritySubdivisions) != PolynomialSign::uncertain) {
    ++stats.coplanarity_rejected;
    return {};
  }
  BernsteinQuartic g[4];
  double lengths[4] = {0.0, 0.0, 0.0, 0.0};
  const int count = make_quartics(g, lengths);
  if (s > 0.0) {
    // Within s of contact, g_i >= -s |n| L_i >= -s N L_i: widen each error by that.
    for (int i = 0; i < count; ++i) g[i].error = add_up(g[i].error, s * normal_bound * lengths[i] * kRoundUp * kRoundUp);
  }
  const AlgebraicVerdict v = algebraic_filter(c, g, count, options.toi_tolerance);
  if (v.outcome == AlgebraicOutcome::separated) {
    ++stats.algebraic_rejected;
    return {};
  }
  if (v.outcome == AlgebraicOutcome::contact) {
    ++stats.algebraic_hits;
    return {true, v.t_lo, v.t_hi, CcdStatus::contact};
  }
  problem.t_begin = v.t_lo;  // [0, t_lo) is excluded
  const InclusionResult r = solve_inclusion(problem, options);
  ++stats.solver_runs;
  stats.solver_boxes += r.boxes;
  if (!r.hit) ++stats.solver_rejected;
  if (r.status == CcdStatus::iteration_limit) ++stats.iteration_limit;
  return {r.hit, r.toi_lower, r.toi_upper, r.status};
}

}  // namespace skelcd::ccd::detail
