#pragma once
// The conservative CCD pipeline shared by vertex-face and edge-edge, after the swept-AABB test
// (docs/ccd.md, "Conservative pipeline"):
//   1. coplanarity filter — the cubic c(t) (with min_separation: |c| > s |n|) certified away from
//   0; 1½. with CcdOptions::relative_boxes, the relative boxes (ccd/detail/relative_boxes.hpp);
//   2. algebraic filter — certified decisions on intervals (with min_separation: widened by it);
//   3. inclusion solver — whatever is left, from the first time the filters could not exclude.

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

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

/// The hull of the coefficients proves one sign on all of [0,1]: cubic_sign's first test, with the
/// finiteness checks it makes.
inline bool certified_sign(const std::array<double, 4>& b, double error) {
  // Written as "b > error" so that NaN falls through; |b| < inf for cubic_sign's isfinite.
  constexpr double kMax = std::numeric_limits<double>::max();
  const bool finite = std::abs(b[0]) <= kMax && std::abs(b[1]) <= kMax && std::abs(b[2]) <= kMax &&
                      std::abs(b[3]) <= kMax;
  const bool positive = b[0] > error && b[1] > error && b[2] > error && b[3] > error;
  const bool negative = -b[0] > error && -b[1] > error && -b[2] > error && -b[3] > error;
  return finite && (positive || negative);
}

/// Some quartic certified negative on all of [0,1].
inline bool certified_negative(const BernsteinQuartic& g) {
  const auto& b = g.coefficients;
  const double e = g.error;
  return -b[0] > e && -b[1] > e && -b[2] > e && -b[3] > e && -b[4] > e;
}
/// The same for the quartic in lane `lane`.
inline bool certified_negative(const QuarticLanes& g, std::size_t lane) {
  const auto& b = g.coefficients;
  const double e = g.error[lane];
  return -b[0][lane] > e && -b[1][lane] > e && -b[2][lane] > e && -b[3][lane] > e &&
         -b[4][lane] > e;
}

// Largest coordinate magnitude of the coplanarity differences under which every difference of the
// query's points has magnitude <= 2^192 (docs/ccd.md), so that every quartic's error bound is
// finite.
inline constexpr double kQuarticScreenMagnitude = 0x1p190;

/// The pipeline after stage 1's screen (trilinear_screen, certified_sign) has failed to certify a
/// sign: from stage 1½ on. conservative_pipeline's parameters; `screen` is the screen of
/// coplanarity_t0/_t1 (its coefficients and magnitude are read), `normal_bound` and `margin` what
/// conservative_pipeline derives from min_separation (both 0 without it).
template <
    typename MakeQuarticInputs,
    typename QuarticsX4,
    typename MakeProblem,
    typename RelativeApart>
CcdResult pipeline_after_screen(
    const DifferenceTriple& coplanarity_t0,
    const DifferenceTriple& coplanarity_t1,
    const TrilinearScreen& screen,
    double normal_bound,
    double margin,
    MakeQuarticInputs&& make_quartic_inputs,
    QuarticsX4&& quartics_x4,
    MakeProblem&& make_problem,
    RelativeApart&& relative_apart,
    const CcdOptions& options,
    CcdStats& stats) {
  const double s = options.min_separation;
  // Stage 1½, the relative boxes: after the cheap coplanarity screen, so that the queries it
  // rejects cost nothing more, and before the exact coplanarity bound, its subdivisions and the
  // quartics, which the queries it removes would reach.
  if (options.relative_boxes && relative_apart()) {
    ++stats.relative_rejected;
    return {};
  }
  BernsteinCubic c{screen.coefficients, trilinear_error(coplanarity_t0, coplanarity_t1)};
  if (s > 0.0) c.error = add_up(c.error, margin);
  if (cubic_sign(c, kCoplanaritySubdivisions) != PolynomialSign::uncertain) {
    ++stats.coplanarity_rejected;
    return {};
  }
  // Stage 2, the inside quartics, two at a time when the coordinates allow.
  QuadrupleDifferences inputs[4];
  double lengths[4] = {0.0, 0.0, 0.0, 0.0};
  // Finite end coefficients mean finite X, Y, Z at both times (each coordinate reaches b_0 or b_3
  // through products and sums, which keep inf and NaN), hence finite points; with the magnitude
  // bound every quartic below is finite with a finite error.
  const bool screened = std::isfinite(c.coefficients[0]) && std::isfinite(c.coefficients[3]) &&
                        screen.magnitude <= kQuarticScreenMagnitude;
  const bool wide = screened && cross_dot_quartics_x4_wide();
  // The differences as QuadrupleDifferences only where they are read: the quartics one or two at
  // a time, or the edge lengths (min_separation).
  int count = wide && s == 0.0 ? 0 : make_quartic_inputs(inputs, s > 0.0 ? lengths : nullptr);
  AlgebraicVerdict v;
  if (wide) {
    // All at once from the query's points, the shared factor pair crossed once, left in lanes
    // for the filter (a third quartic's query fills the fourth lane, which is not read); then
    // the early exit below on the first two, as the pairs take it.
    QuarticLanes lanes;
    const int computed = quartics_x4(lanes);
    assert(count == 0 || count == computed);
    count = computed;
    if (s == 0.0 && std::isfinite(c.error) && std::isfinite(lanes.error[0]) &&
        std::isfinite(lanes.error[1]) &&
        (certified_negative(lanes, 0) || certified_negative(lanes, 1))) {
      ++stats.algebraic_rejected;
      return {};
    }
    if (s > 0.0) {
      // Within s of contact, g_i >= -s |n| L_i >= -s N L_i: widen each error by that.
      for (int i = 0; i < count; ++i) {
        auto& e = lanes.error[static_cast<std::size_t>(i)];
        e = add_up(e, s * normal_bound * lengths[i] * kRoundUp * kRoundUp);
      }
      if (count == 3) lanes.error[3] = lanes.error[2];
    }
    v = algebraic_filter_lanes(c, lanes, count, options.toi_tolerance);
  } else {
    BernsteinQuartic g[4];
    if (screened) {
      cross_dot_quartic_pair(inputs[0], inputs[1], g[0], g[1]);
      // algebraic_filter's first step, on the first two: with every error finite, a quartic
      // certified negative on [0,1] excludes the root interval and the answer is "separated".
      // The others need not be computed.
      if (s == 0.0 && std::isfinite(c.error) && std::isfinite(g[0].error) &&
          std::isfinite(g[1].error) && (certified_negative(g[0]) || certified_negative(g[1]))) {
        ++stats.algebraic_rejected;
        return {};
      }
      if (count == 4) {
        cross_dot_quartic_pair(inputs[2], inputs[3], g[2], g[3]);
      } else {
        BernsteinQuartic unused;
        cross_dot_quartic_pair(inputs[2], inputs[2], g[2], unused);
      }
    } else {
      for (int i = 0; i < count; ++i) g[i] = cross_dot_quartic(inputs[i]);
    }
    if (s > 0.0) {
      // Within s of contact, g_i >= -s |n| L_i >= -s N L_i: widen each error by that.
      for (int i = 0; i < count; ++i)
        g[i].error = add_up(g[i].error, s * normal_bound * lengths[i] * kRoundUp * kRoundUp);
    }
    v = algebraic_filter(c, g, count, options.toi_tolerance);
  }
  if (v.outcome == AlgebraicOutcome::separated) {
    ++stats.algebraic_rejected;
    return {};
  }
  if (v.outcome == AlgebraicOutcome::contact) {
    ++stats.algebraic_hits;
    return {true, v.t_lo, v.t_hi, CcdStatus::contact};
  }
  InclusionProblem problem = make_problem();
  problem.t_begin = v.t_lo;  // [0, t_lo) is excluded
  const InclusionResult r = solve_inclusion(problem, options);
  ++stats.solver_runs;
  stats.solver_boxes += r.boxes;
  if (!r.hit) ++stats.solver_rejected;
  if (r.status == CcdStatus::iteration_limit) ++stats.iteration_limit;
  return {r.hit, r.toi_lower, r.toi_upper, r.status};
}

/// @param coplanarity_t0/_t1 X, Y, Z with c(t) = X . (Y x Z) and n = Y x Z; every point of the
/// query appears in one of them.
/// @param known the query's coplanarity screen when it has already been computed (beside three
/// others, without a contact distance) and certified nothing: the pipeline goes on from there.
/// Null otherwise.
/// @param make_quartic_inputs fills arrays of QuadrupleDifferences and of edge-length bounds L_i
/// and returns how many (3 or 4): at a point within distance s of contact, g_i >= -s |n| L_i
/// (docs/ccd.md). Every vector is a difference of two of the query's points. `lengths` is null
/// when min_separation is 0 (they are not needed).
/// @param quartics_x4 fills a QuarticLanes with the quartics of those inputs, bit for bit, and
/// returns their count (inside_quartic_lanes); called only where cross_dot_quartics_x4_wide().
/// @param make_problem returns the solver's InclusionProblem (only the few queries that reach it
/// pay for it).
/// @param relative_apart returns relative_boxes_apart for the query (asked only with
/// CcdOptions::relative_boxes, of the queries the coplanarity stage leaves).
template <
    typename MakeQuarticInputs,
    typename QuarticsX4,
    typename MakeProblem,
    typename RelativeApart>
CcdResult conservative_pipeline(
    const DifferenceTriple& coplanarity_t0,
    const DifferenceTriple& coplanarity_t1,
    const TrilinearScreen* known,
    MakeQuarticInputs&& make_quartic_inputs,
    QuarticsX4&& quartics_x4,
    MakeProblem&& make_problem,
    RelativeApart&& relative_apart,
    const CcdOptions& options,
    CcdStats& stats) {
  const double s = options.min_separation;
  // Stage 1, the coplanarity cubic. First with an error bound from the largest coordinate
  // magnitudes, >= the exact bound of trilinear_error: when that certifies a sign, so would
  // cubic_sign (same coefficients, smaller error, no subdivision needed). Otherwise the exact
  // bound and cubic_sign as before. A screen computed beside three others (`known`) has certified
  // nothing: on from stage 1½.
  double normal_bound = 0.0;
  double margin = 0.0;
  TrilinearScreen fresh;
  const TrilinearScreen* screen = known;
  if (screen != nullptr) {
    assert(s == 0.0);
  } else {
    fresh = trilinear_screen(coplanarity_t0, coplanarity_t1);
    screen = &fresh;
    if (s > 0.0) {
      // |c(t)| <= s |n(t)| <= s N at any time within s: widen the error by s N (docs/ccd.md).
      normal_bound = cross_norm_bound(coplanarity_t0, coplanarity_t1);
      margin = s * normal_bound * kRoundUp;
    }
    if (certified_sign(
            fresh.coefficients, s > 0.0 ? add_up(fresh.error_upper, margin) : fresh.error_upper)) {
      ++stats.coplanarity_rejected;
      return {};
    }
  }
  return pipeline_after_screen(
      coplanarity_t0,
      coplanarity_t1,
      *screen,
      normal_bound,
      margin,
      make_quartic_inputs,
      quartics_x4,
      make_problem,
      relative_apart,
      options,
      stats);
}

}  // namespace skelcd::ccd::detail
