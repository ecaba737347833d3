// The conservative kernels against the code they replaced (issue 14): the pipeline as it was before
// the screened coplanarity bound, the paired quartics, the early exit on the first two quartics and
// the two-lane algebraic filter, kept here verbatim, must give the same CcdResult bits and the same
// CcdStats on every query — random, near-degenerate, scaled to tiny and huge coordinates,
// non-finite, and with min_separation — but for the bracket of a contact the algebraic filter
// certifies: since 2026-11-30 it is narrowed by regula falsi where the cubic is monotone
// (docs/ccd.md, "Narrowing a certain contact"), so the two brackets must share a point (each
// holds the first contact) and the new one be no wider than the tolerance or the old one. And the
// pieces one by one: the screen's bound against the exact bound, the paired quartics against
// cross_dot_quartic, the narrowing against the exact roots of exact cubics.

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/detail/algebraic_filter.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/inclusion_solver.hpp"
#include "ccd/detail/lanes.hpp"
#include "ccd/detail/rational_polynomial.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "ccd/filters.hpp"
#include "tests/ccd/cloth_funnel.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

using detail::add_up;
using detail::AlgebraicOutcome;
using detail::AlgebraicVerdict;
using detail::BernsteinQuartic;
using detail::kEps;
using detail::kRoundUp;
using detail::kUnderflowUnit;
using detail::rounding_bound;

// ---- The replaced code (ccd/ at ee161e6), verbatim but for names. ----

// Deepest halving of [0,1] (width 2^-40) and most intervals looked at before handing over.
constexpr int kMaxDepth = 40;
constexpr int kNodeBudget = 256;
constexpr int kMaxQuartics = 4;

// Certified sign of a Bernstein polynomial over its interval: the hull of the coefficients.
template <std::size_t M>
int hull_sign(const std::array<double, M>& b, double e) {
  bool pos = true;
  bool neg = true;
  for (const double x : b) {
    pos = pos && x > e;  // NaN: neither
    neg = neg && -x > e;
  }
  return pos ? 1 : (neg ? -1 : 0);
}

// The two ends of the interval: b[0] and b[M-1] are the values there.
template <std::size_t M>
bool certain_sign_change(const std::array<double, M>& b, double e) {
  return (b[0] > e && -b[M - 1] > e) || (-b[0] > e && b[M - 1] > e);
}

// de Casteljau at 1/2. New coefficients are convex combinations of the old (old errors carry over)
// computed with at most n = M - 1 roundings of averages of values bounded by max|b| + e (rounding
// lemma, k = n), plus underflow of the halvings.
template <std::size_t M>
double halve(
    const std::array<double, M>& b,
    double e,
    std::array<double, M>& left,
    std::array<double, M>& right) {
  std::array<double, M> w = b;
  double m = 0.0;
  for (const double x : b) m = std::max(m, std::abs(x));
  left[0] = w[0];
  right[M - 1] = w[M - 1];
  // Fully unrolled, so that w lives in registers: left as a loop, the levels were stored as
  // vectors and re-read across two stores (a store-forwarding stall per level, a tenth of the
  // cloth-ball CCD). The operations and their order are the same.
#pragma GCC unroll 8
  for (std::size_t level = 1; level < M; ++level) {
#pragma GCC unroll 8
    for (std::size_t i = 0; i + level < M; ++i) w[i] = (w[i] + w[i + 1]) * 0.5;
    left[level] = w[0];
    right[M - 1 - level] = w[M - 1 - level];
  }
  const auto n = static_cast<int>(M) - 1;
  return add_up(add_up(e, rounding_bound(n, add_up(m, e))), n * kUnderflowUnit);
}

struct Node {
  double lo, hi;
  int depth;
  std::array<double, 4> c;
  double c_err;
  std::array<std::array<double, 5>, kMaxQuartics> g;
  std::array<double, kMaxQuartics> g_err;
};

// A certain root of c in [lo, hi] (certified sign change): narrow toward the first root while the
// signs allow. Every root of c in the interval is a contact here, so the first root is the TOI.
AlgebraicVerdict narrow(
    double lo, double hi, std::array<double, 4> c, double e, double toi_tolerance) {
  for (int step = 0; step < 64 && hi - lo > toi_tolerance; ++step) {
    std::array<double, 4> left, right;
    const double e2 = halve(c, e, left, right);
    const double mid = 0.5 * (lo + hi);
    if (!(lo < mid && mid < hi)) break;
    if (hull_sign(left, e2) != 0) {
      // No root in the left half: the sign change is in the right half.
      lo = mid;
      c = right;
    } else if (certain_sign_change(left, e2)) {
      hi = mid;
      c = left;
    } else {
      break;  // the left half may hold a root or not: keep [lo, hi]
    }
    e = e2;
  }
  return {AlgebraicOutcome::contact, lo, hi};
}

AlgebraicVerdict reference_algebraic_filter(
    const BernsteinCubic& c, const BernsteinQuartic* g, int count, double toi_tolerance) {
  assert(count >= 0 && count <= kMaxQuartics);
  // Overflowed bounds (coordinates near the double range) prove nothing: leave it to the solver.
  bool finite = std::isfinite(c.error);
  for (int i = 0; i < count; ++i) finite = finite && std::isfinite(g[i].error);
  if (!finite) return {AlgebraicOutcome::undecided, 0.0, 1.0};
  // Depth first, earlier half first: the left half is processed next, the right half waits.
  std::array<Node, kMaxDepth + 2> waiting;
  int size = 0;
  Node node;
  node.lo = 0.0;
  node.hi = 1.0;
  node.depth = 0;
  node.c = c.coefficients;
  node.c_err = c.error;
  for (int i = 0; i < count; ++i) {
    node.g[static_cast<std::size_t>(i)] = g[i].coefficients;
    node.g_err[static_cast<std::size_t>(i)] = g[i].error;
  }
  int visited = 0;
  for (;;) {
    // Coplanarity excluded here, or some inside condition failing throughout?
    bool excluded = hull_sign(node.c, node.c_err) != 0;
    bool all_positive = true;
    for (int i = 0; i < count && !excluded; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      const int s = hull_sign(node.g[ii], node.g_err[ii]);
      if (s < 0) excluded = true;
      if (s <= 0) all_positive = false;
    }
    if (excluded) {
      if (size == 0) break;
      node = waiting[static_cast<std::size_t>(--size)];
      continue;
    }
    if (all_positive && certain_sign_change(node.c, node.c_err)) {
      return narrow(node.lo, node.hi, node.c, node.c_err, toi_tolerance);
    }
    const double mid = 0.5 * (node.lo + node.hi);
    if (++visited > kNodeBudget || node.depth >= kMaxDepth || !(node.lo < mid && mid < node.hi)) {
      // Undecided; everything before node.lo was excluded.
      return {AlgebraicOutcome::undecided, node.lo, 1.0};
    }
    Node& right = waiting[static_cast<std::size_t>(size++)];
    right.lo = mid;
    right.hi = node.hi;
    right.depth = node.depth + 1;
    std::array<double, 4> left_c;
    right.c_err = halve(node.c, node.c_err, left_c, right.c);
    node.c = left_c;
    node.c_err = right.c_err;
    for (int i = 0; i < count; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      std::array<double, 5> left_g;
      right.g_err[ii] = halve(node.g[ii], node.g_err[ii], left_g, right.g[ii]);
      node.g[ii] = left_g;
      node.g_err[ii] = right.g_err[ii];
    }
    node.hi = mid;
    node.depth = right.depth;
  }
  return {AlgebraicOutcome::separated, 1.0, 1.0};
}

// trilinear_determinant before it was split into coefficients and error (clustering and
// segmentation use it through moving_orientation_cubic).
BernsteinCubic reference_trilinear_determinant(
    const detail::DifferenceTriple& t0, const detail::DifferenceTriple& t1) {
  using namespace detail;
  // Blossom of the trilinear det: b_i averages the dets d_ijk = X_i . (Y_j x Z_k) with i + j + k
  // factors taken at t = 1, and the permanents likewise. Each det is evaluated as
  // x0 c0 + x1 c1 + x2 c2, c = y x z, two at a time: lane 0 takes Y_0, lane 1 Y_1.
  const Lanes3 y = lanes3(t0.y, t1.y);
  const Lanes3 z0 = lanes3(t0.z, t0.z);
  const Lanes3 z1 = lanes3(t1.z, t1.z);
  const Lanes3 x0 = lanes3(t0.x, t0.x);
  const Lanes3 x1 = lanes3(t1.x, t1.x);
  const Lanes3 c_z0 = cross(y, z0);  // {Y0 x Z0, Y1 x Z0}
  const Lanes3 c_z1 = cross(y, z1);  // {Y0 x Z1, Y1 x Z1}
  const Lanes3 ay = lane_abs(y);
  const Lanes3 p_z0 = cross_permanent(ay, lane_abs(z0));
  const Lanes3 p_z1 = cross_permanent(ay, lane_abs(z1));
  const Lanes3 ax0 = lane_abs(x0), ax1 = lane_abs(x1);
  const Lanes d0x0 = dot(x0, c_z0);  // {d000, d010}
  const Lanes d1x0 = dot(x1, c_z0);  // {d100, d110}
  const Lanes d0x1 = dot(x0, c_z1);  // {d001, d011}
  const Lanes d1x1 = dot(x1, c_z1);  // {d101, d111}
  const Lanes p0x0 = dot(ax0, p_z0), p1x0 = dot(ax1, p_z0);
  const Lanes p0x1 = dot(ax0, p_z1), p1x1 = dot(ax1, p_z1);
  // The middle coefficients {(d100 + d010 + d001) / 3, (d011 + d101 + d110) / 3}, summed in that
  // order.
  const Lanes mid =
      ((Lanes{d1x0[0], d0x1[1]} + Lanes{d0x0[1], d1x1[0]}) + Lanes{d0x1[0], d1x0[1]}) / 3.0;
  const Lanes mid_perm =
      ((Lanes{p1x0[0], p0x1[1]} + Lanes{p0x0[1], p1x1[0]}) + Lanes{p0x1[0], p1x0[1]}) / 3.0;
  BernsteinCubic f;
  f.coefficients = {d0x0[0], mid[0], mid[1], d1x1[1]};
  const double perm = std::max({p0x0[0], mid_perm[0], mid_perm[1], p1x1[1]});
  // Rounding count per product term: difference 1 each for x, y, z; y*z 3; the cross-product
  // difference 4; x * (.) 6; the two sums of the dot 8; the two sums and the /3 of the average 11.
  const double relative = rounding_bound(11, perm);
  // Underflow: each of the 6 products y*z may lose kUnderflowUnit, then scaled by |x| <= mx; each
  // x*(.) product and the /3 may lose one more.
  const double mx = std::max(t0.x.cwiseAbs().maxCoeff(), t1.x.cwiseAbs().maxCoeff());
  // 16 kUnderflowUnit (1 + mx) = 2^-1070 (1 + mx), computed without a subnormal product.
  const double underflow = detail::times_subnormal_power_of_two<1070>(1.0 + mx);
  f.error = add_up(relative, underflow);
  return f;
}

// conservative_pipeline before the screen, the pairs and the early exit.
template <typename MakeQuartics>
CcdResult reference_pipeline(
    const detail::DifferenceTriple& coplanarity_t0,
    const detail::DifferenceTriple& coplanarity_t1,
    MakeQuartics&& make_quartics,
    detail::InclusionProblem& problem,
    const CcdOptions& options,
    CcdStats& stats) {
  const double s = options.min_separation;
  BernsteinCubic c = detail::trilinear_determinant(coplanarity_t0, coplanarity_t1);
  double normal_bound = 0.0;
  if (s > 0.0) {
    normal_bound = detail::cross_norm_bound(coplanarity_t0, coplanarity_t1);
    c.error = add_up(c.error, s * normal_bound * kRoundUp);
  }
  if (cubic_sign(c, detail::kCoplanaritySubdivisions) != PolynomialSign::uncertain) {
    ++stats.coplanarity_rejected;
    return {};
  }
  BernsteinQuartic g[4];
  double lengths[4] = {0.0, 0.0, 0.0, 0.0};
  const int count = make_quartics(g, lengths);
  if (s > 0.0) {
    for (int i = 0; i < count; ++i)
      g[i].error = add_up(g[i].error, s * normal_bound * lengths[i] * kRoundUp * kRoundUp);
  }
  const AlgebraicVerdict v = reference_algebraic_filter(c, g, count, options.toi_tolerance);
  if (v.outcome == AlgebraicOutcome::separated) {
    ++stats.algebraic_rejected;
    return {};
  }
  if (v.outcome == AlgebraicOutcome::contact) {
    ++stats.algebraic_hits;
    return {true, v.t_lo, v.t_hi, CcdStatus::contact};
  }
  problem.t_begin = v.t_lo;
  const detail::InclusionResult r = detail::solve_inclusion(problem, options);
  ++stats.solver_runs;
  stats.solver_boxes += r.boxes;
  if (!r.hit) ++stats.solver_rejected;
  if (r.status == CcdStatus::iteration_limit) ++stats.iteration_limit;
  return {r.hit, r.toi_lower, r.toi_upper, r.status};
}

CcdResult reference_conservative(
    const VertexFaceQuery& q, const CcdOptions& options, CcdStats& stats) {
  if (swept_aabbs_disjoint(q, options.min_separation)) {
    ++stats.aabb_rejected;
    return {};
  }
  const detail::DifferenceTriple t0{q.v_t0 - q.f0_t0, q.f1_t0 - q.f0_t0, q.f2_t0 - q.f0_t0};
  const detail::DifferenceTriple t1{q.v_t1 - q.f0_t1, q.f1_t1 - q.f0_t1, q.f2_t1 - q.f0_t1};
  const auto quartics = [&](BernsteinQuartic* g, double* lengths) {
    const Eigen::Vector3d bc_t0 = q.f2_t0 - q.f1_t0, bc_t1 = q.f2_t1 - q.f1_t1;
    const Eigen::Vector3d ca_t0 = q.f0_t0 - q.f2_t0, ca_t1 = q.f0_t1 - q.f2_t1;
    g[0] = detail::cross_dot_quartic({t0.y, t0.z, t0.y, t0.x, t1.y, t1.z, t1.y, t1.x});
    g[1] = detail::cross_dot_quartic(
        {t0.y, t0.z, bc_t0, q.v_t0 - q.f1_t0, t1.y, t1.z, bc_t1, q.v_t1 - q.f1_t1});
    g[2] = detail::cross_dot_quartic(
        {t0.y, t0.z, ca_t0, q.v_t0 - q.f2_t0, t1.y, t1.z, ca_t1, q.v_t1 - q.f2_t1});
    lengths[0] = detail::norm_bound(t0.y, t1.y);
    lengths[1] = detail::norm_bound(bc_t0, bc_t1);
    lengths[2] = detail::norm_bound(ca_t0, ca_t1);
    return 3;
  };
  detail::InclusionProblem problem;
  problem.d_t0 = t0.x;
  problem.e_t0 = q.f0_t0 - q.f1_t0;
  problem.g_t0 = q.f0_t0 - q.f2_t0;
  problem.d_t1 = t1.x;
  problem.e_t1 = q.f0_t1 - q.f1_t1;
  problem.g_t1 = q.f0_t1 - q.f2_t1;
  problem.triangle_domain = true;
  return reference_pipeline(t0, t1, quartics, problem, options, stats);
}

CcdResult reference_conservative(
    const EdgeEdgeQuery& q, const CcdOptions& options, CcdStats& stats) {
  if (swept_aabbs_disjoint(q, options.min_separation)) {
    ++stats.aabb_rejected;
    return {};
  }
  const detail::DifferenceTriple t0{q.eb0_t0 - q.ea0_t0, q.ea1_t0 - q.ea0_t0, q.eb1_t0 - q.eb0_t0};
  const detail::DifferenceTriple t1{q.eb0_t1 - q.ea0_t1, q.ea1_t1 - q.ea0_t1, q.eb1_t1 - q.eb0_t1};
  const auto quartics = [&](BernsteinQuartic* g, double* lengths) {
    g[0] = detail::cross_dot_quartic({t0.x, t0.z, t0.y, t0.z, t1.x, t1.z, t1.y, t1.z});
    g[1] = detail::cross_dot_quartic(
        {q.ea1_t0 - q.eb0_t0, t0.z, t0.y, t0.z, q.ea1_t1 - q.eb0_t1, t1.z, t1.y, t1.z});
    g[2] = detail::cross_dot_quartic({t0.x, t0.y, t0.y, t0.z, t1.x, t1.y, t1.y, t1.z});
    g[3] = detail::cross_dot_quartic(
        {t0.y, q.eb1_t0 - q.ea0_t0, t0.y, t0.z, t1.y, q.eb1_t1 - q.ea0_t1, t1.y, t1.z});
    lengths[0] = lengths[1] = detail::norm_bound(t0.z, t1.z);
    lengths[2] = lengths[3] = detail::norm_bound(t0.y, t1.y);
    return 4;
  };
  detail::InclusionProblem problem;
  problem.d_t0 = q.ea0_t0 - q.eb0_t0;
  problem.e_t0 = t0.y;
  problem.g_t0 = q.eb0_t0 - q.eb1_t0;
  problem.d_t1 = q.ea0_t1 - q.eb0_t1;
  problem.e_t1 = t1.y;
  problem.g_t1 = q.eb0_t1 - q.eb1_t1;
  problem.triangle_domain = false;
  return reference_pipeline(t0, t1, quartics, problem, options, stats);
}

// ---- Comparison. ----

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The two brackets of one contact: sharing a point (each holds the first contact), `mine` no
// wider than the tolerance or `theirs`.
bool same_contact(
    double mine_lo, double mine_hi, double theirs_lo, double theirs_hi, double tolerance) {
  return mine_lo <= theirs_hi && theirs_lo <= mine_hi && mine_lo <= mine_hi &&
         mine_hi - mine_lo <= std::max(tolerance, theirs_hi - theirs_lo);
}

::testing::AssertionResult same_result(const CcdResult& a, const CcdResult& b, double tolerance) {
  const bool bits = same_bits(a.toi_lower, b.toi_lower) && same_bits(a.toi_upper, b.toi_upper);
  const bool contact = a.hit && a.status == CcdStatus::contact &&
                       same_contact(a.toi_lower, a.toi_upper, b.toi_lower, b.toi_upper, tolerance);
  if (a.hit == b.hit && (bits || contact) && a.status == b.status) {
    return ::testing::AssertionSuccess();
  }
  return ::testing::AssertionFailure()
         << "hit " << a.hit << " / " << b.hit << ", toi [" << a.toi_lower << ", " << a.toi_upper
         << "] / [" << b.toi_lower << ", " << b.toi_upper << "], status "
         << static_cast<int>(a.status) << " / " << static_cast<int>(b.status);
}

::testing::AssertionResult same_stats(const CcdStats& a, const CcdStats& b) {
  const std::int64_t x[] = {
      a.queries,
      a.aabb_rejected,
      a.coplanarity_rejected,
      a.algebraic_rejected,
      a.algebraic_hits,
      a.solver_runs,
      a.solver_rejected,
      a.solver_boxes,
      a.iteration_limit,
      a.hits};
  const std::int64_t y[] = {
      b.queries,
      b.aabb_rejected,
      b.coplanarity_rejected,
      b.algebraic_rejected,
      b.algebraic_hits,
      b.solver_runs,
      b.solver_rejected,
      b.solver_boxes,
      b.iteration_limit,
      b.hits};
  for (int i = 0; i < 10; ++i) {
    if (x[i] != y[i])
      return ::testing::AssertionFailure() << "counter " << i << ": " << x[i] << " / " << y[i];
  }
  return ::testing::AssertionSuccess();
}

// What stage each query left at, over a set: every stage must see some traffic for the comparison
// to mean anything.
struct Coverage {
  CcdStats stats;
  int checked = 0;
};

// One query both ways, with stats, and through the after-swept-AABB entry point when that applies.
void compare(
    bool vertex_face,
    const std::array<Eigen::Vector3d, 8>& p,
    const CcdOptions& options,
    Coverage& coverage,
    const char* what) {
  const VertexFaceQuery vf{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  const EdgeEdgeQuery ee{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]};
  CcdStats mine, theirs;
  const CcdResult a = vertex_face ? vertex_face_ccd(vf, Accuracy::conservative, options, mine)
                                  : edge_edge_ccd(ee, Accuracy::conservative, options, mine);
  CcdResult b = vertex_face ? reference_conservative(vf, options, theirs)
                            : reference_conservative(ee, options, theirs);
  ++theirs.queries;
  if (b.hit) ++theirs.hits;
  ASSERT_TRUE(same_result(a, b, options.toi_tolerance)) << what << (vertex_face ? " vf" : " ee");
  ASSERT_TRUE(same_stats(mine, theirs)) << what << (vertex_face ? " vf" : " ee");
  if (options.min_separation == 0.0 &&
      !(vertex_face ? swept_aabbs_disjoint(vf) : swept_aabbs_disjoint(ee))) {
    const CcdResult c = vertex_face
                            ? vertex_face_ccd_after_swept_aabbs(vf, Accuracy::conservative, options)
                            : edge_edge_ccd_after_swept_aabbs(ee, Accuracy::conservative, options);
    ASSERT_TRUE(same_result(c, b, options.toi_tolerance)) << what << " after swept AABBs";
  }
  coverage.stats += mine;
  ++coverage.checked;
}

// Each stage must have decided some of the queries of a set.
void expect_every_stage_seen(const Coverage& c) {
  EXPECT_GT(c.stats.coplanarity_rejected, 0);
  EXPECT_GT(c.stats.algebraic_rejected, 0);
  EXPECT_GT(c.stats.algebraic_hits, 0);
}

std::array<Eigen::Vector3d, 8> transformed(
    std::array<Eigen::Vector3d, 8> p, double scale, const Eigen::Vector3d& shift) {
  for (auto& x : p) x = x * scale + shift;
  return p;
}

TEST(KernelEquivalence, RandomMixAtEveryScale) {
  // The property-test mix (near-degenerate, contacts nudged by ulps, coplanar motion), then the
  // same queries scaled by powers of two (exact) toward underflow and overflow: 2^-1000 puts the
  // products in the subnormal range, 2^190 and beyond switch the pair path off (the screen's
  // magnitude bound), 2^300 overflows the quartics' bounds.
  // The scaled copies often reach the solver (the bounds stop proving anything near the ends of
  // the range); a small iteration budget keeps that quick and is the same for both sides.
  test::RandomQueryGenerator gen(7);
  Coverage coverage;
  CcdOptions scaled_options;
  scaled_options.max_iterations = 200;
  for (int i = 0; i < 20000; ++i) {
    const test::RandomQuery q = gen.next();
    compare(q.vertex_face, q.points, {}, coverage, "mix");
    if (i % 16 == 0) {
      for (const double scale :
           {0x1p-1000, 0x1p-500, 0x1p-60, 0x1p60, 0x1p189, 0x1p191, 0x1p250, 0x1p300}) {
        compare(
            q.vertex_face,
            transformed(q.points, scale, Eigen::Vector3d::Zero()),
            scaled_options,
            coverage,
            "scaled");
      }
    }
  }
  expect_every_stage_seen(coverage);
  EXPECT_GT(coverage.stats.solver_runs, 0);
}

TEST(KernelEquivalence, UniformQueries) {
  test::RandomQueryGenerator gen(8);
  Coverage coverage;
  for (int i = 0; i < 20000; ++i) {
    const test::RandomQuery q = gen.next_uniform();
    compare(q.vertex_face, q.points, {}, coverage, "uniform");
  }
  expect_every_stage_seen(coverage);
}

TEST(KernelEquivalence, HardCaseFamiliesWithAndWithoutSeparation) {
  Coverage coverage;
  for (const auto& c : test::hard_cases(11, 2)) {
    compare(c.vertex_face, c.points, {}, coverage, c.family.c_str());
    CcdOptions options;
    options.min_separation = 1e-3;
    compare(c.vertex_face, c.points, options, coverage, c.family.c_str());
  }
  expect_every_stage_seen(coverage);
  EXPECT_GT(coverage.stats.solver_runs, 0);
}

TEST(KernelEquivalence, ClothFunnelStep) {
  Coverage coverage;
  for (const char* kind : {"vf", "ee"}) {
    for (const auto& c : test::load_cloth_funnel(kind)) {
      std::array<Eigen::Vector3d, 8> p;
      if (c.vertex_face) {
        const VertexFaceQuery v = c.vf();
        p = {v.v_t0, v.f0_t0, v.f1_t0, v.f2_t0, v.v_t1, v.f0_t1, v.f1_t1, v.f2_t1};
      } else {
        const EdgeEdgeQuery e = c.ee();
        p = {e.ea0_t0, e.ea1_t0, e.eb0_t0, e.eb1_t0, e.ea0_t1, e.ea1_t1, e.eb0_t1, e.eb1_t1};
      }
      compare(c.vertex_face, p, {}, coverage, "cloth funnel");
    }
  }
  EXPECT_GT(coverage.checked, 300);
}

TEST(KernelEquivalence, NonFiniteAndDegenerateInput) {
  // Every coordinate of a query in turn made inf, -inf or NaN; and queries whose points coincide,
  // do not move, or sit on a coordinate plane (exact zeros everywhere, zero error bounds).
  test::RandomQueryGenerator gen(9);
  Coverage coverage;
  CcdOptions options;
  options.max_iterations = 200;  // non-finite input runs the solver to its budget, both sides
  const double specials[] = {
      std::numeric_limits<double>::infinity(),
      -std::numeric_limits<double>::infinity(),
      std::numeric_limits<double>::quiet_NaN(),
      0x1p1000,
      -0x1p1020,
      0x1p-1074};
  for (int i = 0; i < 200; ++i) {
    const test::RandomQuery q = gen.next();
    for (int k = 0; k < 24; ++k) {
      auto p = q.points;
      p[static_cast<std::size_t>(k / 3)][k % 3] = specials[static_cast<std::size_t>((i + k) % 6)];
      compare(q.vertex_face, p, options, coverage, "special");
    }
  }
  const Eigen::Vector3d o = Eigen::Vector3d::Zero(), x = Eigen::Vector3d::UnitX(),
                        y = Eigen::Vector3d::UnitY();
  for (const bool vf : {true, false}) {
    compare(vf, {o, o, o, o, o, o, o, o}, {}, coverage, "all at the origin");
    compare(vf, {o, x, y, x + y, o, x, y, x + y}, {}, coverage, "flat, still");
    compare(vf, {x, o, x, y, x, o, x, y}, {}, coverage, "coincident points");
    compare(vf, {0.5 * x, o, x, y, 0.5 * x + y, o, x, y}, {}, coverage, "in-plane slide");
  }
}

// ---- The pieces. ----

TEST(KernelEquivalence, ScreenBoundIsAboveTheExactBound) {
  // trilinear_determinant is what it was; trilinear_screen's coefficients are its coefficients,
  // bit for bit, and the screen's error bound is >= the exact one whenever finite; when it
  // certifies a sign, so does cubic_sign.
  test::RandomQueryGenerator gen(10);
  std::mt19937_64 rng(10);
  int certified = 0;
  for (int i = 0; i < 50000; ++i) {
    const test::RandomQuery q = gen.next();
    const auto& p = q.points;
    const double scale = std::ldexp(1.0, std::uniform_int_distribution<int>(-1060, 300)(rng));
    const detail::DifferenceTriple t0{
        (p[0] - p[1]) * scale, (p[2] - p[1]) * scale, (p[3] - p[1]) * scale};
    const detail::DifferenceTriple t1{
        (p[4] - p[5]) * scale, (p[6] - p[5]) * scale, (p[7] - p[5]) * scale};
    const detail::TrilinearScreen screen = detail::trilinear_screen(t0, t1);
    const BernsteinCubic exact = detail::trilinear_determinant(t0, t1);
    const BernsteinCubic before = reference_trilinear_determinant(t0, t1);
    for (std::size_t k = 0; k < 4; ++k)
      ASSERT_TRUE(same_bits(exact.coefficients[k], before.coefficients[k]));
    ASSERT_TRUE(same_bits(exact.error, before.error));
    for (std::size_t k = 0; k < 4; ++k)
      ASSERT_TRUE(same_bits(screen.coefficients[k], exact.coefficients[k]));
    if (std::isfinite(screen.error_upper)) {
      ASSERT_GE(screen.error_upper, exact.error) << i;
    }
    if (detail::certified_sign(screen.coefficients, screen.error_upper)) {
      ++certified;
      ASSERT_NE(cubic_sign(exact, 0), PolynomialSign::uncertain) << i;
    }
  }
  EXPECT_GT(certified, 1000);
}

/// Random quadruples of differences for the quartics' tests: coordinates in [-s, s]; for some i
/// a vector repeated (i % 5 == 0) or zero (i % 7 == 0).
class RandomQuadruples {
 public:
  explicit RandomQuadruples(std::uint64_t seed) : rng_(seed) {}
  /// A scale from subnormal products to large ones.
  double scale() { return std::ldexp(1.0, std::uniform_int_distribution<int>(-540, 180)(rng_)); }
  detail::QuadrupleDifferences next(int i, double s) {
    detail::QuadrupleDifferences x{vec(s), vec(s), vec(s), vec(s), vec(s), vec(s), vec(s), vec(s)};
    if (i % 5 == 0) x.c_t0 = x.a_t0;
    if (i % 7 == 0) x.d_t1 = Eigen::Vector3d::Zero();
    return x;
  }

 private:
  Eigen::Vector3d vec(double s) {
    const double x = u_(rng_), y = u_(rng_), z = u_(rng_);
    return Eigen::Vector3d(x, y, z) * s;
  }
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> u_{-1.0, 1.0};
};

TEST(KernelEquivalence, PairedQuarticsAreCrossDotQuarticBitForBit) {
  RandomQuadruples random(12);
  for (int i = 0; i < 20000; ++i) {
    const double s = random.scale();
    detail::QuadrupleDifferences q[2];
    for (auto& x : q) x = random.next(i, s);
    BernsteinQuartic g0, g1;
    detail::cross_dot_quartic_pair(q[0], q[1], g0, g1);
    const BernsteinQuartic r0 = detail::cross_dot_quartic(q[0]),
                           r1 = detail::cross_dot_quartic(q[1]);
    for (std::size_t k = 0; k < 5; ++k) {
      ASSERT_TRUE(same_bits(g0.coefficients[k], r0.coefficients[k])) << i;
      ASSERT_TRUE(same_bits(g1.coefficients[k], r1.coefficients[k])) << i;
    }
    ASSERT_TRUE(same_bits(g0.error, r0.error)) << i;
    ASSERT_TRUE(same_bits(g1.error, r1.error)) << i;
  }
}

TEST(KernelEquivalence, InsideQuarticsFromThePointsAreCrossDotQuarticBitForBit) {
  // inside_quartics_x4 in both of its builds takes the differences and the shared factor pair
  // its own way: each quartic must still be cross_dot_quartic of the quadruple the kernels
  // define (vertex_face.cpp, edge_edge.cpp), bit for bit, at every scale, with points repeated
  // (degenerate features) and some coordinates zero.
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-540, 180);
  for (const bool baseline : {false, true}) {
    detail::force_baseline_quartics(baseline);
    for (int i = 0; i < 20000; ++i) {
      const double s = std::ldexp(1.0, exponent(rng));
      std::array<Eigen::Vector3d, 8> p;
      for (auto& x : p) x = Eigen::Vector3d(u(rng), u(rng), u(rng)) * s;
      if (i % 5 == 0) p[3] = p[1];
      if (i % 7 == 0) p[6].x() = 0.0;
      if (i % 11 == 0) p[4] = p[0] + Eigen::Vector3d(0x1p-52, 0.0, 0.0) * s;
      // Every point on one line (here the x axis): every cross product is 0, the quartics' bound
      // its underflow term alone, which the largest coordinate sets.
      if (i % 13 == 0) {
        for (auto& x : p) x.tail<2>().setZero();
      }
      const std::array<const Eigen::Vector3d*, 4> t0{&p[0], &p[1], &p[2], &p[3]};
      const std::array<const Eigen::Vector3d*, 4> t1{&p[4], &p[5], &p[6], &p[7]};
      for (const bool edge_edge : {false, true}) {
        // The quadruples at one end (points a, b, c, d), written as the kernels define them.
        const auto quads = [&](const Eigen::Vector3d& a,
                               const Eigen::Vector3d& b,
                               const Eigen::Vector3d& c,
                               const Eigen::Vector3d& d) {
          std::array<std::array<Eigen::Vector3d, 4>, 4> q;
          if (edge_edge) {  // (a0, a1, b0, b1): w = b0 - a0, d_a = a1 - a0, d_b = b1 - b0
            q[0] = {c - a, d - c, b - a, d - c};
            q[1] = {b - c, d - c, b - a, d - c};
            q[2] = {c - a, b - a, b - a, d - c};
            q[3] = {b - a, d - a, b - a, d - c};
          } else {  // (v, f0, f1, f2)
            q[0] = {c - b, d - b, c - b, a - b};
            q[1] = {c - b, d - b, d - c, a - c};
            q[2] = {c - b, d - b, b - d, a - d};
            q[3] = q[2];
          }
          return q;
        };
        const auto q0 = quads(p[0], p[1], p[2], p[3]);
        const auto q1 = quads(p[4], p[5], p[6], p[7]);
        BernsteinQuartic g[4];
        const int count = detail::inside_quartics_x4(
            edge_edge ? detail::InsideQuartics::edge_edge : detail::InsideQuartics::vertex_face,
            t0,
            t1,
            g);
        ASSERT_EQ(count, edge_edge ? 4 : 3);
        for (std::size_t k = 0; k < 4; ++k) {
          const detail::QuadrupleDifferences q{
              q0[k][0], q0[k][1], q0[k][2], q0[k][3], q1[k][0], q1[k][1], q1[k][2], q1[k][3]};
          const BernsteinQuartic r = detail::cross_dot_quartic(q);
          for (std::size_t c = 0; c < 5; ++c) {
            ASSERT_TRUE(same_bits(g[k].coefficients[c], r.coefficients[c]))
                << i << (edge_edge ? " EE" : " VF") << " quartic " << k
                << (baseline ? " baseline" : "");
          }
          ASSERT_TRUE(same_bits(g[k].error, r.error)) << i << " quartic " << k;
        }
      }
    }
  }
  detail::force_baseline_quartics(false);
}

TEST(KernelEquivalence, KernelsGiveTheSameAnswersWithFourQuarticsAtOnce) {
  // The conservative pipeline computes its four inside quartics at once where
  // cross_dot_quartics_x4_wide() holds, and two pairs (the second only past the early exit)
  // otherwise: the same answers, bit for bit, and the same stage counts, on the random mix, the
  // hard cases and the cloth-funnel step. On a CPU without AVX2 both runs take the pairs.
  struct Item {
    bool vertex_face;
    std::array<Eigen::Vector3d, 8> points;
  };
  std::vector<Item> items;
  test::RandomQueryGenerator generator(61);
  for (int n = 0; n < 4000; ++n) {
    const test::RandomQuery q = generator.next();
    items.push_back({q.vertex_face, q.points});
  }
  for (const test::HardCase& c : test::hard_cases(9, 2)) items.push_back({c.vertex_face, c.points});
  for (const char* kind : {"vf", "ee"}) {
    for (const auto& c : test::load_cloth_funnel(kind)) {
      if (c.vertex_face) {
        const VertexFaceQuery v = c.vf();
        items.push_back(
            {true, {v.v_t0, v.f0_t0, v.f1_t0, v.f2_t0, v.v_t1, v.f0_t1, v.f1_t1, v.f2_t1}});
      } else {
        const EdgeEdgeQuery e = c.ee();
        items.push_back(
            {false,
             {e.ea0_t0, e.ea1_t0, e.eb0_t0, e.eb1_t0, e.ea0_t1, e.ea1_t1, e.eb0_t1, e.eb1_t1}});
      }
    }
  }
  CcdOptions options;
  options.max_iterations = 2000;
  const auto run = [&](bool baseline, CcdStats& stats) {
    detail::force_baseline_quartics(baseline);
    std::vector<CcdResult> out;
    for (const Item& it : items) {
      const auto& p = it.points;
      out.push_back(
          it.vertex_face ? vertex_face_ccd(
                               {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]},
                               Accuracy::conservative,
                               options,
                               stats)
                         : edge_edge_ccd(
                               {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]},
                               Accuracy::conservative,
                               options,
                               stats));
    }
    detail::force_baseline_quartics(false);
    return out;
  };
  CcdStats wide_stats, baseline_stats;
  const std::vector<CcdResult> wide = run(false, wide_stats);
  const std::vector<CcdResult> baseline = run(true, baseline_stats);
  for (std::size_t i = 0; i < items.size(); ++i) {
    ASSERT_EQ(wide[i].hit, baseline[i].hit) << i;
    ASSERT_EQ(wide[i].status, baseline[i].status) << i;
    ASSERT_TRUE(same_bits(wide[i].toi_lower, baseline[i].toi_lower)) << i;
    ASSERT_TRUE(same_bits(wide[i].toi_upper, baseline[i].toi_upper)) << i;
  }
  EXPECT_EQ(wide_stats.algebraic_rejected, baseline_stats.algebraic_rejected);
  EXPECT_EQ(wide_stats.algebraic_hits, baseline_stats.algebraic_hits);
  EXPECT_EQ(wide_stats.solver_runs, baseline_stats.solver_runs);
  EXPECT_EQ(wide_stats.solver_boxes, baseline_stats.solver_boxes);
  // The quartics decide many of them either way: the comparison has teeth.
  EXPECT_GT(wide_stats.algebraic_rejected, 500);
  EXPECT_GT(wide_stats.algebraic_hits, 500);
}

TEST(KernelEquivalence, AlgebraicFilterOnRandomPolynomials) {
  // Coefficients of mixed signs near the error bound, 0 to 4 quartics: every outcome (separated,
  // contact with narrowing, undecided at the budget or depth) against the replaced filter.
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int outcomes[3] = {0, 0, 0};
  for (int i = 0; i < 50000; ++i) {
    BernsteinCubic c;
    for (double& b : c.coefficients) b = u(rng);
    c.error = std::ldexp(1.0, std::uniform_int_distribution<int>(-60, -1)(rng));
    if (i % 11 == 0) c.error = 0.0;
    const int count = i % 5;
    BernsteinQuartic g[4];
    for (int k = 0; k < count; ++k) {
      for (double& b : g[k].coefficients) b = u(rng) + (i % 3 == 0 ? 0.6 : 0.0);
      g[k].error = std::ldexp(1.0, std::uniform_int_distribution<int>(-60, -1)(rng));
    }
    const double tolerance = i % 2 == 0 ? 1e-6 : 0.25;
    const AlgebraicVerdict a = detail::algebraic_filter(c, g, count, tolerance);
    const AlgebraicVerdict b = reference_algebraic_filter(c, g, count, tolerance);
    ASSERT_EQ(a.outcome, b.outcome) << i;
    if (a.outcome == AlgebraicOutcome::contact) {
      ASSERT_TRUE(same_contact(a.t_lo, a.t_hi, b.t_lo, b.t_hi, tolerance))
          << i << ": [" << a.t_lo << ", " << a.t_hi << "] / [" << b.t_lo << ", " << b.t_hi << "]";
    } else {
      ASSERT_TRUE(same_bits(a.t_lo, b.t_lo)) << i;
      ASSERT_TRUE(same_bits(a.t_hi, b.t_hi)) << i;
    }
    ++outcomes[static_cast<int>(a.outcome)];
  }
  for (const int n : outcomes) EXPECT_GT(n, 100);
}

TEST(KernelEquivalence, AlgebraicFilterGivesTheSameVerdictWithItsQuarticsInFourLanes) {
  // With three or four quartics and AVX2 the filter carries them in the four lanes of one vector
  // instead of two pairs: the same verdict and the same bracket, bit for bit, on random
  // polynomials of every outcome and on coefficients from the subnormal range to 2^300. On a CPU
  // without AVX2 both runs take the pairs.
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int outcomes[3] = {0, 0, 0};
  int handed_over = 0;
  for (int i = 0; i < 40000; ++i) {
    const double scale =
        i % 4 == 0 ? std::ldexp(1.0, std::uniform_int_distribution<int>(-1060, 300)(rng)) : 1.0;
    BernsteinCubic c;
    for (double& b : c.coefficients) b = u(rng) * scale;
    c.error = std::ldexp(scale, std::uniform_int_distribution<int>(-60, -1)(rng));
    if (i % 11 == 0) c.error = 0.0;
    const int count = 3 + i % 2;
    BernsteinQuartic g[4];
    for (int k = 0; k < count; ++k) {
      for (double& b : g[k].coefficients) b = (u(rng) + (i % 3 == 0 ? 0.6 : 0.0)) * scale;
      g[k].error = std::ldexp(scale, std::uniform_int_distribution<int>(-60, -1)(rng));
    }
    const double tolerance = i % 2 == 0 ? 1e-6 : 0.25;
    detail::force_baseline_quartics(true);
    const AlgebraicVerdict pairs = detail::algebraic_filter(c, g, count, tolerance);
    detail::force_baseline_quartics(false);
    const AlgebraicVerdict lanes = detail::algebraic_filter(c, g, count, tolerance);
    ASSERT_EQ(lanes.outcome, pairs.outcome) << i;
    ASSERT_TRUE(same_bits(lanes.t_lo, pairs.t_lo)) << i;
    ASSERT_TRUE(same_bits(lanes.t_hi, pairs.t_hi)) << i;
    ++outcomes[static_cast<int>(lanes.outcome)];
    if (detail::cross_dot_quartics_x4_wide()) {
      // The quartics handed over in lanes, as the pipeline's four-lane path does (a third
      // quartic's lane repeated in the fourth): the same again.
      detail::QuarticLanes in_lanes;
      for (std::size_t k = 0; k < 4; ++k) {
        const BernsteinQuartic& q =
            g[std::min<std::size_t>(k, static_cast<std::size_t>(count) - 1)];
        for (std::size_t j = 0; j < 5; ++j) in_lanes.coefficients[j][k] = q.coefficients[j];
        in_lanes.error[k] = q.error;
      }
      const AlgebraicVerdict handed = detail::algebraic_filter_lanes(c, in_lanes, count, tolerance);
      ASSERT_EQ(handed.outcome, pairs.outcome) << i;
      ASSERT_TRUE(same_bits(handed.t_lo, pairs.t_lo)) << i;
      ASSERT_TRUE(same_bits(handed.t_hi, pairs.t_hi)) << i;
      ++handed_over;
    }
  }
  for (const int n : outcomes) EXPECT_GT(n, 100);
  // Where the CPU has AVX2 (CI's does) every polynomial went through the lanes too.
  EXPECT_TRUE(handed_over == 40000 || !detail::cross_dot_quartics_x4_wide());
}

// Whether the exact cubic with Bernstein coefficients x has a root in [0, t): its first root on
// [0, 1], isolated by the exact reference's machinery (rational_polynomial.hpp), compared with t.
bool exact_root_before(const std::array<mpq_class, 4>& x, const mpq_class& t) {
  const detail::RationalPolynomial p(
      {x[0], 3 * (x[1] - x[0]), 3 * (x[0] - 2 * x[1] + x[2]), -x[0] + 3 * x[1] - 3 * x[2] + x[3]});
  if (p.is_zero()) return sgn(t) > 0;  // roots everywhere
  const detail::RationalPolynomial f = detail::square_free(p);
  const std::vector<detail::RealRoot> roots = detail::isolate_roots_in_unit_interval(f);
  if (roots.empty()) return false;
  const detail::RealRoot& r = roots.front();
  if (r.rational || r.hi <= t) return r.lo < t;
  if (r.lo >= t) return false;
  // t inside the isolating interval (lo, hi), where f changes sign once: the root is before t
  // exactly when f already has changed sign at t.
  const int at_t = f.sign_at(t);
  return at_t != 0 && at_t != f.sign_at(r.lo);
}

// Cubics with a certain sign change on [0, 1] and no quartic: the filter reports a contact whose
// bracket must hold a root, checked in rational arithmetic: the exact Bernstein polynomial's signs
// at t_lo and t_hi differ or one of them is 0. A monotone cubic has one root, the first: with
// error 0 its bracket must be narrowed to the tolerance (and, from Newton's guess, mostly to a
// 32nd of it); with an error bound (2^-10 … 2^-49) the narrowing falls back where signs near the
// root are not certain, and the bracket must still start at no later root. Monotone and not,
// steep and nearly flat at the root (the middle coefficients on the chord).
TEST(KernelEquivalence, NarrowingHoldsTheExactFirstRoot) {
  std::mt19937_64 rng(20261130);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<int> offset(-2, 2);
  using Exact = std::array<mpq_class, 4>;
  const auto exact_at = [](const Exact& c, const mpq_class& t) -> mpq_class {
    const mpq_class a = 1 - t;
    return mpq_class(c[0] * a * a * a + 3 * c[1] * a * a * t) +
           mpq_class(3 * c[2] * a * t * t + c[3] * t * t * t);
  };
  int monotone = 0, fine = 0, with_error = 0, not_monotone = 0, roots_checked = 0;
  for (int i = 0; i < 30000; ++i) {
    BernsteinCubic c;
    for (double& b : c.coefficients) b = u(rng);
    if (i % 3 == 0) {
      // Monotone: increasing coefficients from a negative start.
      std::sort(c.coefficients.begin(), c.coefficients.end());
      if (i % 6 == 0) std::reverse(c.coefficients.begin(), c.coefficients.end());
    }
    if (i % 5 == 0)
      c.coefficients[1] = c.coefficients[2] = 0.5 * (c.coefficients[0] + c.coefficients[3]);
    // The last third carries an error bound e (2^-10 … 2^-49), and the exact cubic is another
    // one within it: each coefficient moved by -e, -e/2, 0, e/2 or e. Near the root signs are
    // then not certain, and a guess taken for a bound (Newton's, uncertified) would miss the
    // exact root; the narrowing must fall back to regula falsi or halving from what it certified.
    c.error = i >= 20000 ? std::ldexp(1.0, -10 - i % 40) : 0.0;
    const auto& b = c.coefficients;
    Exact x;
    for (std::size_t k = 0; k < 4; ++k)
      x[k] = mpq_class(b[k]) + mpq_class(c.error) * offset(rng) / 2;
    if (!((b[0] > 0.0 && b[3] < 0.0) || (b[0] < 0.0 && b[3] > 0.0))) continue;
    // A sign change certain despite the error (the filter's bound at the root is c.error).
    if (!(std::min(std::abs(b[0]), std::abs(b[3])) > 4.0 * c.error)) continue;
    const double tolerance = i % 2 == 0 ? 1e-6 : 1e-3;
    const AlgebraicVerdict v = detail::algebraic_filter(c, nullptr, 0, tolerance);
    ASSERT_EQ(v.outcome, AlgebraicOutcome::contact) << i;
    ASSERT_LE(v.t_lo, v.t_hi) << i;
    const mpq_class lo(v.t_lo), hi(v.t_hi);
    const int s_lo = sgn(exact_at(x, lo));
    const int s_hi = sgn(exact_at(x, hi));
    ASSERT_TRUE(s_lo == 0 || s_hi == 0 || s_lo != s_hi)
        << i << ": no root in [" << v.t_lo << ", " << v.t_hi << "]";
    // No earlier root: for a monotone cubic the sign at t_lo is the sign at 0 (or 0 there).
    const bool increasing = x[0] < x[1] && x[1] < x[2] && x[2] < x[3];
    const bool decreasing = x[0] > x[1] && x[1] > x[2] && x[2] > x[3];
    // No root of the exact cubic before the bracket, monotone or not.
    ASSERT_FALSE(exact_root_before(x, lo)) << i << ": a root before " << v.t_lo;
    roots_checked += sgn(exact_at(x, 0)) != 0 ? 1 : 0;
    if (!(increasing || decreasing)) {
      ++not_monotone;
      continue;
    }
    ASSERT_TRUE(s_lo == 0 || s_lo == sgn(exact_at(x, 0))) << i << ": a root before " << v.t_lo;
    if (c.error == 0.0) {
      // Monotone with error 0: narrowed all the way, and (Newton's guess certified a 64th of the
      // tolerance either side) mostly to a 32nd of it.
      ++monotone;
      ASSERT_LE(v.t_hi - v.t_lo, tolerance) << i;
      fine += v.t_hi - v.t_lo <= tolerance / 30.0 ? 1 : 0;
    } else {
      ++with_error;
    }
  }
  EXPECT_GT(monotone, 2000);
  EXPECT_GT(fine, monotone * 9 / 10);
  EXPECT_GT(with_error, 1000);
  EXPECT_GT(not_monotone, 2000);
  EXPECT_GT(roots_checked, 5000);
}

}  // namespace
}  // namespace skelcd::ccd
