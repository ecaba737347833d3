// The algebraic stage of conservative CCD (see algebraic_filter.hpp and docs/ccd.md).

#include "ccd/detail/algebraic_filter.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "ccd/detail/float_bounds.hpp"
#include "ccd/detail/lanes.hpp"

// Four-double vectors pass between the inline helpers below; where the baseline ABI has no AVX
// they are split, which is what the note is about. Nothing crosses a library boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace skelcd::ccd::detail {
namespace {

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
double halve(const std::array<double, M>& b, double e, std::array<double, M>& left, std::array<double, M>& right) {
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

// halve for two or four polynomials at once (L: Lanes or Lanes4), lane k halving the k-th: the
// same operations per lane.
template <std::size_t M, class L>
[[gnu::always_inline]] inline L halve(
    const std::array<L, M>& b, const L& e, std::array<L, M>& left, std::array<L, M>& right) {
  std::array<L, M> w = b;
  L m{};
  for (const L& x : b) m = lane_max(m, lane_abs(x));  // std::max(m, std::abs(x))
  left[0] = w[0];
  right[M - 1] = w[M - 1];
#pragma GCC unroll 8
  for (std::size_t level = 1; level < M; ++level) {
#pragma GCC unroll 8
    for (std::size_t i = 0; i + level < M; ++i) w[i] = (w[i] + w[i + 1]) * 0.5;
    left[level] = w[0];
    right[M - 1 - level] = w[M - 1 - level];
  }
  const auto n = static_cast<int>(M) - 1;
  // add_up and rounding_bound per lane.
  const L bound = (static_cast<double>(n + 1) * kEps) * ((m + e) * kRoundUp);
  return ((e + bound) * kRoundUp + n * kUnderflowUnit) * kRoundUp;
}

// Bits of "every coefficient > e" and of "every coefficient < -e", per lane.
template <std::size_t M, class L, class B>
[[gnu::always_inline]] inline void hull_masks(
    const std::array<L, M>& b, const L& e, B& pos, B& neg) {
  pos = b[0] > e;
  neg = -b[0] > e;
  for (std::size_t i = 1; i < M; ++i) {
    pos &= b[i] > e;
    neg &= -b[i] > e;
  }
}

// The quartics travel in groups of W lanes (L: two or four doubles), quartic W p + k in lane k
// of group p.
template <class L, std::size_t kGroups>
struct Node {
  double lo, hi;
  int depth;
  std::array<double, 4> c;
  double c_err;
  std::array<std::array<L, 5>, kGroups> g;
  std::array<L, kGroups> g_err;
};

AlgebraicVerdict narrow(
    double lo, double hi, std::array<double, 4> c, double e, double toi_tolerance);
int monotone(const std::array<double, 4>& c, double e);

/// Bisection of narrow(): the sign change kept by halving the Bernstein coefficients. With
/// `until_monotone`, as soon as the half kept is certified monotone, narrow() takes over on it
/// (it holds the first root and a certain sign change, as every half kept does); narrow() itself
/// halves without it, so the two never call each other twice.
AlgebraicVerdict narrow_by_halving(
    double lo,
    double hi,
    std::array<double, 4> c,
    double e,
    double toi_tolerance,
    bool until_monotone = false) {
  for (int step = 0; step < 64 && hi - lo > toi_tolerance; ++step) {
    if (until_monotone && step != 0 && monotone(c, e) != 0) {
      return narrow(lo, hi, c, e, toi_tolerance);
    }
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

/// +1 (−1) when every exact cubic within e of the coefficients c is strictly increasing
/// (decreasing) on its interval: the Bernstein coefficients of the derivative, 3 (c_{i+1} − c_i),
/// all of one sign. Each difference of the exact coefficients lies within 2e of c_{i+1} − c_i,
/// which its rounding moves by at most eps |d|. 0 otherwise (NaN included).
int monotone(const std::array<double, 4>& c, double e) {
  int up = 0;
  int down = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    const double d = c[i + 1] - c[i];
    const double slack = add_up(2.0 * e, 2.0 * kEps * std::abs(d));
    up += d > slack ? 1 : 0;
    down += -d > slack ? 1 : 0;
  }
  return up == 3 ? 1 : (down == 3 ? -1 : 0);
}

/// de Casteljau's scheme for the Bernstein cubic c at s, with a = fl(1 − s) for 1 − s: the value
/// and the two points of the level below it (b012, b123), whose difference times 3 is the
/// derivative there.
struct CubicAt {
  double value, b012, b123;
};

[[gnu::always_inline]] inline CubicAt de_casteljau(const std::array<double, 4>& c, double s) {
  const double a = 1.0 - s;
  const double b01 = a * c[0] + s * c[1];
  const double b12 = a * c[1] + s * c[2];
  const double b23 = a * c[2] + s * c[3];
  const double b012 = a * b01 + s * b12;
  const double b123 = a * b12 + s * b23;
  return {a * b012 + s * b123, b012, b123};
}

/// The certified sign of every exact cubic within e of the Bernstein coefficients c at parameter
/// s in (0, 1) (0: not certified), and the computed value. de Casteljau with a = fl(1 − s): a
/// differs from 1 − s by at most eps (1 − s), which moves each weight a^(3−i) s^i by at most
/// ((1 + eps)³ − 1) of itself, so the polynomial with a in place of 1 − s is within 3.01 eps M of
/// the exact one (M = max |c_i|, the weights summing to 1); each leaf-to-root chain of the scheme
/// sees 6 roundings, so the evaluation is within 7 eps (1 + 4 eps) M of that (rounding_bound with
/// the permanent ≤ (1 + eps)³ M); the coefficients' error e passes through weights summing to at
/// most (1 + eps)³; and each of the 12 products may add kUnderflowUnit. 16 eps M covers the first
/// two with room, and 16 kUnderflowUnit the last.
int certified_sign_at(const std::array<double, 4>& c, double e, double s, double& value) {
  value = de_casteljau(c, s).value;
  const double m =
      std::max(std::max(std::abs(c[0]), std::abs(c[1])), std::max(std::abs(c[2]), std::abs(c[3])));
  const double bound =
      add_up(add_up(e * (1.0 + 8.0 * kEps), 16.0 * kEps * m), 16.0 * kUnderflowUnit);
  return value > bound ? 1 : (-value > bound ? -1 : 0);
}

/// Where safeguarded Newton iteration in plain double puts the root of the Bernstein cubic c on
/// (0, 1), starting from s in (0, 1): a guess only, never a bound. Each step evaluates c and its
/// derivative by de Casteljau; a step that leaves the bracket the signs keep (from (0, 1)), or a
/// derivative of 0, halves it instead. Stops once a step moves by at most `settle`.
double newton_guess(const std::array<double, 4>& c, bool positive_first, double s, double settle) {
  double s_lo = 0.0, s_hi = 1.0;
  for (int step = 0; step < 8; ++step) {
    const CubicAt at = de_casteljau(c, s);
    if (at.value == 0.0) return s;
    ((at.value > 0.0) == positive_first ? s_lo : s_hi) = s;
    double next = s - at.value / (3.0 * (at.b123 - at.b012));
    if (!(next > s_lo && next < s_hi)) next = 0.5 * (s_lo + s_hi);  // NaN too
    const bool settled = std::abs(next - s) <= settle;
    s = next;
    if (settled) break;
  }
  return s;
}

/// A certain root of c in [lo, hi] (certified sign change): narrow toward the first root while the
/// signs allow. Every root of c in the interval is a contact here, so the first root is the TOI.
/// When every exact cubic within e is monotone on [lo, hi] it has one root there, and a sign
/// certified at any point says on which side of it the root lies. So: guess the root with a few
/// Newton steps in plain double (newton_guess), and certify the signs a 64th of the tolerance
/// either side of the guess — two certified evaluations, where regula falsi with the Illinois
/// step needed about seven. Each sign certified there narrows the bracket whatever it says; when
/// the two do not close it to the tolerance, regula falsi with the Illinois step (the value kept at
/// an end retained twice is halved) goes on from the bracket they left. Where a sign cannot be
/// certified, or the cubic is not monotone, the bracket is narrowed by halving
/// (narrow_by_halving) from there. The result is a bracket of doubles around the exact root:
/// lo + s (hi − lo), with hi − lo a power of two, is rounded outwards.
AlgebraicVerdict narrow(
    double lo, double hi, std::array<double, 4> c, double e, double toi_tolerance) {
  if (!(hi - lo > toi_tolerance)) return {AlgebraicOutcome::contact, lo, hi};
  if (monotone(c, e) == 0) return narrow_by_halving(lo, hi, c, e, toi_tolerance, true);
  const double width = hi - lo;
  // The signs at the two ends are certain (certain_sign_change): s_lo keeps c's sign at 0.
  double s_lo = 0.0, s_hi = 1.0;
  double v_lo = c[0], v_hi = c[3];
  const bool positive_first = c[0] > 0.0;
  const auto bracket = [&] {
    const double t_lo = s_lo == 0.0 ? lo : next_down(lo + s_lo * width);
    const double t_hi = s_hi == 1.0 ? hi : next_up(lo + s_hi * width);
    return AlgebraicVerdict{AlgebraicOutcome::contact, std::max(t_lo, lo), std::min(t_hi, hi)};
  };
  // A certified sign at s moves the end on its side of the root to s.
  const auto certify = [&](double s) {
    double value = 0.0;
    const int sign = certified_sign_at(c, e, s, value);
    if (sign == 0) return false;
    if ((sign > 0) == positive_first) {
      s_lo = std::max(s_lo, s);
      if (s_lo == s) v_lo = value;
    } else {
      s_hi = std::min(s_hi, s);
      if (s_hi == s) v_hi = value;
    }
    return true;
  };
  {
    // A bracket of a 32nd of the tolerance: about as wide as regula falsi's used to end (its
    // median on the cloth-ball step's contacts, 4e-8 for 1e-6), where Newton has converged.
    const double half = (toi_tolerance / width) * (1.0 / 64.0);
    double guess = v_lo / (v_lo - v_hi);  // regula falsi's first point
    if (!(guess > 0.0 && guess < 1.0)) guess = 0.5;
    guess = newton_guess(c, positive_first, guess, 0.125 * half);
    const double below = guess - half;
    const double above = guess + half;
    const bool certified_below = !(below > 0.0) || certify(below);
    const bool certified_above = !(above < 1.0) || certify(above);
    const AlgebraicVerdict v = bracket();
    if (certified_below && certified_above && !(v.t_hi - v.t_lo > toi_tolerance)) return v;
  }
  int kept = 0;  // +1: the low end was kept last time, −1: the high end
  for (int step = 0; step < 64; ++step) {
    const AlgebraicVerdict v = bracket();
    if (!(v.t_hi - v.t_lo > toi_tolerance)) return v;
    double s = s_lo + (s_hi - s_lo) * (v_lo / (v_lo - v_hi));
    if (!(s > s_lo && s < s_hi)) s = 0.5 * (s_lo + s_hi);
    if (!(s > s_lo && s < s_hi)) return v;
    double value = 0.0;
    const int sign = certified_sign_at(c, e, s, value);
    if (sign == 0) break;
    if ((sign > 0) == positive_first) {
      s_lo = s;
      v_lo = value;
      if (kept == 1) v_hi *= 0.5;
      kept = 1;
    } else {
      s_hi = s;
      v_hi = value;
      if (kept == -1) v_lo *= 0.5;
      kept = -1;
    }
  }
  // A sign not certified near the root, or 64 steps: halving on the interval reached so far.
  // Its Bernstein coefficients come from the node's by two de Casteljau splits; rather than
  // carry those, halve from the node while the certified bracket [s_lo, s_hi] still holds.
  const AlgebraicVerdict v = bracket();
  const AlgebraicVerdict halved = narrow_by_halving(lo, hi, c, e, toi_tolerance);
  // Both contain the root: their intersection does too.
  const double t_lo = std::max(v.t_lo, halved.t_lo);
  const double t_hi = std::min(v.t_hi, halved.t_hi);
  return t_lo <= t_hi ? AlgebraicVerdict{AlgebraicOutcome::contact, t_lo, t_hi} : halved;
}

struct CrossPerm {
  Eigen::Vector3d value;
  Eigen::Vector3d permanent;
};

CrossPerm cross_perm(const Eigen::Vector3d& x, const Eigen::Vector3d& y) {
  const Eigen::Vector3d xa = x.cwiseAbs();
  const Eigen::Vector3d ya = y.cwiseAbs();
  return {x.cross(y), Eigen::Vector3d(xa[1] * ya[2] + xa[2] * ya[1], xa[2] * ya[0] + xa[0] * ya[2],
                                      xa[0] * ya[1] + xa[1] * ya[0])};
}

}  // namespace

namespace {

/// C(4, i): b_i is the average of that many blossom evaluations.
constexpr double kQuarticTerms[5] = {1.0, 4.0, 6.0, 4.0, 1.0};

/// cross_dot_quartic's error bound from the largest level average of the permanents `p` and the
/// largest coordinate magnitude `m` of the quadruple. Rounding count per product term:
/// differences 1; a_y b_z 3; cross difference 4; product of two cross components 9; the dot's two
/// sums 11; the running sum of at most 6 terms (from 0) 17; the division 18. Underflow: a cross
/// component may lose 2 units, then be multiplied by another one (at most 2 m^2), plus one unit
/// per product and the division: 64 kUnderflowUnit (1 + m^2) = 2^-1068 (1 + m^2), computed
/// without a subnormal product.
inline double quartic_bound(double p, double m) {
  return add_up(rounding_bound(18, p), times_subnormal_power_of_two<1068>(1.0 + m * m));
}

}  // namespace

BernsteinQuartic cross_dot_quartic(const QuadrupleDifferences& q) {
  // Blossom: b_i is the average of the C(4, i) evaluations with i of the 4 factors at t = 1.
  // Factor pairs: A x B with (A, B) at times (mask & 1, mask & 2), C x D at (mask & 4, mask & 8).
  const CrossPerm ab[4] = {cross_perm(q.a_t0, q.b_t0), cross_perm(q.a_t1, q.b_t0), cross_perm(q.a_t0, q.b_t1),
                           cross_perm(q.a_t1, q.b_t1)};
  const CrossPerm cd[4] = {cross_perm(q.c_t0, q.d_t0), cross_perm(q.c_t1, q.d_t0), cross_perm(q.c_t0, q.d_t1),
                           cross_perm(q.c_t1, q.d_t1)};
  static constexpr int kBits[4] = {0, 1, 1, 2};
  std::array<double, 5> sum{};
  std::array<double, 5> perm{};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const auto level = static_cast<std::size_t>(kBits[i] + kBits[j]);
      const Eigen::Vector3d& x = ab[i].value;
      const Eigen::Vector3d& y = cd[j].value;
      const Eigen::Vector3d& px = ab[i].permanent;
      const Eigen::Vector3d& py = cd[j].permanent;
      sum[level] += (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2];
      perm[level] += (px[0] * py[0] + px[1] * py[1]) + px[2] * py[2];
    }
  }
  BernsteinQuartic out;
  double p = 0.0;
  for (std::size_t i = 0; i < 5; ++i) {
    out.coefficients[i] = sum[i] / kQuarticTerms[i];
    p = std::max(p, perm[i] / kQuarticTerms[i]);
  }
  double m = 0.0;
  for (const auto* v : {&q.a_t0, &q.b_t0, &q.c_t0, &q.d_t0, &q.a_t1, &q.b_t1, &q.c_t1, &q.d_t1}) {
    m = std::max(m, v->cwiseAbs().maxCoeff());
  }
  out.error = quartic_bound(p, m);
  return out;
}

namespace {

/// The end of cross_dot_quartic for the W lanes of L: coefficient i of every lane from the level
/// sums `sum` (coefficient(i, value)), and lane k's bound from the permanents' level sums `perm`
/// and its largest coordinate magnitude m[k] (bound(k, e)).
template <class L, std::size_t W, class Coefficient, class Bound>
[[gnu::always_inline]] inline void store_quartics(
    const L (&sum)[5],
    const L (&perm)[5],
    const L& m,
    const Coefficient& coefficient,
    const Bound& bound) {
  L p{};
  for (std::size_t i = 0; i < 5; ++i) {
    coefficient(i, sum[i] / kQuarticTerms[i]);
    p = lane_max(p, perm[i] / kQuarticTerms[i]);
  }
  for (std::size_t k = 0; k < W; ++k) bound(k, quartic_bound(p[k], m[k]));
}

/// The four factor products of A x B over the pairs of end times, lane by lane: product k takes
/// A at time k & 1 and B at time k >> 1 (`x`, `y` the factors at t0 and t1), with its permanent.
template <class L>
[[gnu::always_inline]] inline void factor_products(
    const LaneVec3<L> (&x)[2],
    const LaneVec3<L> (&y)[2],
    LaneVec3<L> (&product)[4],
    LaneVec3<L> (&permanent)[4]) {
  const LaneVec3<L> ax[2] = {lane_abs(x[0]), lane_abs(x[1])};
  const LaneVec3<L> ay[2] = {lane_abs(y[0]), lane_abs(y[1])};
  for (int k = 0; k < 4; ++k) {
    const int i = k & 1, j = k >> 1;
    product[k] = cross(x[i], y[j]);
    permanent[k] = cross_permanent(ax[i], ay[j]);
  }
}

/// The blossom's level sums of (A x B) . (C x D) from the factor products (factor_products):
/// sum[l] adds ab[i] . cd[j] over the (i, j) whose times add up to l, i outer, j inner (the
/// order every build keeps, for the same bits); perm the same on the permanents.
template <class L>
[[gnu::always_inline]] inline void level_sums(
    const LaneVec3<L> (&ab)[4],
    const LaneVec3<L> (&ab_perm)[4],
    const LaneVec3<L> (&cd)[4],
    const LaneVec3<L> (&cd_perm)[4],
    L (&sum)[5],
    L (&perm)[5]) {
  static constexpr int kBits[4] = {0, 1, 1, 2};
#pragma GCC unroll 4
  for (int i = 0; i < 4; ++i) {
#pragma GCC unroll 4
    for (int j = 0; j < 4; ++j) {
      const int level = kBits[i] + kBits[j];
      sum[level] += dot(ab[i], cd[j]);
      perm[level] += dot(ab_perm[i], cd_perm[j]);
    }
  }
}

/// cross_dot_quartic of q(k) into g(k) for the two lanes of L (k < 2): lane k goes through the
/// scalar code's operations in the same order (detail/lanes.hpp). (Four quadruples in four lanes
/// were gathered here too until the quartics came from the points, inside_quartics_x4.)
template <class L, class Source, class Target>
[[gnu::always_inline]] inline void quartics_body(const Source& q, const Target& g) {
  constexpr std::size_t W = 2;
  const auto gather = [&](Eigen::Vector3d QuadrupleDifferences::*m) {
    return lanes_of<L, 2>({&(q(0).*m), &(q(1).*m)});
  };
  using Q = QuadrupleDifferences;
  using L3 = LaneVec3<L>;
  const L3 a[2] = {gather(&Q::a_t0), gather(&Q::a_t1)};
  const L3 b[2] = {gather(&Q::b_t0), gather(&Q::b_t1)};
  const L3 c[2] = {gather(&Q::c_t0), gather(&Q::c_t1)};
  const L3 d[2] = {gather(&Q::d_t0), gather(&Q::d_t1)};
  // Factor pairs: A x B with (A, B) at times (mask & 1, mask & 2), C x D at (mask & 4, mask & 8).
  L3 ab[4], ab_perm[4], cd[4], cd_perm[4];
  factor_products(a, b, ab, ab_perm);
  factor_products(c, d, cd, cd_perm);
  L sum[5] = {};
  L perm[5] = {};
  level_sums(ab, ab_perm, cd, cd_perm, sum, perm);
  // The largest coordinate magnitude of each quadruple (finite by the precondition, so any order
  // of comparisons finds the same value).
  L m{};
  for (int t = 0; t < 2; ++t) {
    m = lane_max(
        m,
        lane_max(lane_max(max_abs(a[t]), max_abs(b[t])), lane_max(max_abs(c[t]), max_abs(d[t]))));
  }
  store_quartics<L, W>(
      sum,
      perm,
      m,
      [&](std::size_t i, const L& value) __attribute__((always_inline)) {
        for (std::size_t k = 0; k < W; ++k) g(k).coefficients[i] = value[k];
      },
      [&](std::size_t k, double e) __attribute__((always_inline)) { g(k).error = e; });
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define SKELCD_QUARTICS_AVX2 1

using LaneIndex4 = std::int64_t __attribute__((vector_size(32)));

/// Lanes (v[i0], v[i1], v[i2], v[i3]) (one vpermpd).
template <int i0, int i1, int i2, int i3>
[[gnu::always_inline]] inline Lanes4 pick(const Lanes4& v) {
  return __builtin_shuffle(v, LaneIndex4{i0, i1, i2, i3});
}

/// Lane k: point hi_k minus point lo_k, of the four points' coordinates in lanes `p`.
template <int h0, int h1, int h2, int h3, int l0, int l1, int l2, int l3>
[[gnu::always_inline]] inline LaneVec3<Lanes4> differences(const LaneVec3<Lanes4>& p) {
  return {
      pick<h0, h1, h2, h3>(p.x) - pick<l0, l1, l2, l3>(p.x),
      pick<h0, h1, h2, h3>(p.y) - pick<l0, l1, l2, l3>(p.y),
      pick<h0, h1, h2, h3>(p.z) - pick<l0, l1, l2, l3>(p.z)};
}

/// Lane k of each coordinate in all four lanes.
template <int k>
[[gnu::always_inline]] inline LaneVec3<Lanes4> splat(const LaneVec3<Lanes4>& v) {
  return {pick<k, k, k, k>(v.x), pick<k, k, k, k>(v.y), pick<k, k, k, k>(v.z)};
}

/// inside_quartics_x4 built for AVX2. Each quartic is (A x B) . (C x D) over the four pairs of
/// end times; one pair of factors differs per quartic (lane k: quartic k), the other is n's, the
/// same for all: EE's (C, D), VF's (A, B). The varying pair's differences come from the points
/// in lanes; the shared pair is crossed once for its four pairs of times (lane k: times k & 1,
/// k >> 1, as quartics_body's factor pairs) and each result spread over the lanes. The dot
/// products are quartics_body's, in its order, with the same operands: the same bits.
template <InsideQuartics kWhich>
[[gnu::target("avx2")]] void inside_quartics_avx2(
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    QuarticLanes& g) {
  using L = Lanes4;
  using L3 = LaneVec3<L>;
  const auto in_lanes =
      [](const std::array<const Eigen::Vector3d*, 4>& p) __attribute__((always_inline)) {
    return lanes_of<L, 4>({p[0], p[1], p[2], p[3]});
  };
  const L3 points[2] = {in_lanes(at_t0), in_lanes(at_t1)};
  constexpr bool kEdgeEdge = kWhich == InsideQuartics::edge_edge;
  // The varying pair at each end. EE, points (a0, a1, b0, b1): A = b0 - a0, a1 - b0, b0 - a0,
  // a1 - a0 and B = b1 - b0, b1 - b0, a1 - a0, b1 - a0. VF, points (v, f0, f1, f2): C = f1 - f0,
  // f2 - f1, f0 - f2, f0 - f2 and D = v - f0, v - f1, v - f2, v - f2.
  L3 first[2], second[2];
  for (int t = 0; t < 2; ++t) {
    if constexpr (kEdgeEdge) {
      first[t] = differences<2, 1, 2, 1, 0, 2, 0, 0>(points[t]);
      second[t] = differences<3, 3, 1, 3, 2, 2, 0, 0>(points[t]);
    } else {
      first[t] = differences<2, 3, 1, 1, 1, 2, 3, 3>(points[t]);
      second[t] = differences<0, 0, 0, 0, 1, 2, 3, 3>(points[t]);
    }
  }
  // The shared pair (EE: d_a = a1 - a0, d_b = b1 - b0; VF: f1 - f0, f2 - f0) at each end.
  constexpr int kS1Hi = kEdgeEdge ? 1 : 2, kS1Lo = kEdgeEdge ? 0 : 1;
  constexpr int kS2Hi = 3, kS2Lo = kEdgeEdge ? 2 : 1;
  const Eigen::Vector3d s1[2] = {*at_t0[kS1Hi] - *at_t0[kS1Lo], *at_t1[kS1Hi] - *at_t1[kS1Lo]};
  const Eigen::Vector3d s2[2] = {*at_t0[kS2Hi] - *at_t0[kS2Lo], *at_t1[kS2Hi] - *at_t1[kS2Lo]};
  // Lane k: s1 at time k & 1, s2 at time k >> 1.
  const L3 r{
      L{s1[0][0], s1[1][0], s1[0][0], s1[1][0]},
      L{s1[0][1], s1[1][1], s1[0][1], s1[1][1]},
      L{s1[0][2], s1[1][2], s1[0][2], s1[1][2]}};
  const L3 q{
      L{s2[0][0], s2[0][0], s2[1][0], s2[1][0]},
      L{s2[0][1], s2[0][1], s2[1][1], s2[1][1]},
      L{s2[0][2], s2[0][2], s2[1][2], s2[1][2]}};
  const L3 shared_all = cross(r, q);
  const L3 shared_perm_all = cross_permanent(lane_abs(r), lane_abs(q));
  const L3 shared[4] = {
      splat<0>(shared_all), splat<1>(shared_all), splat<2>(shared_all), splat<3>(shared_all)};
  const L3 shared_perm[4] = {
      splat<0>(shared_perm_all),
      splat<1>(shared_perm_all),
      splat<2>(shared_perm_all),
      splat<3>(shared_perm_all)};
  L3 own[4], own_perm[4];
  factor_products(first, second, own, own_perm);
  L sum[5] = {};
  L perm[5] = {};
  if constexpr (kEdgeEdge) {
    level_sums(own, own_perm, shared, shared_perm, sum, perm);
  } else {
    level_sums(shared, shared_perm, own, own_perm, sum, perm);
  }
  L m{};
  double shared_m = 0.0;
  for (int t = 0; t < 2; ++t) {
    m = lane_max(m, lane_max(max_abs(first[t]), max_abs(second[t])));
    shared_m =
        std::max(shared_m, std::max(s1[t].cwiseAbs().maxCoeff(), s2[t].cwiseAbs().maxCoeff()));
  }
  m = lane_max(m, L{shared_m, shared_m, shared_m, shared_m});
  // Into lanes: the coefficients as vectors, the bounds lane by lane.
  store_quartics<L, 4>(
      sum,
      perm,
      m,
      [&](std::size_t i, const L& value) __attribute__((always_inline)) {
        std::memcpy(g.coefficients[i].data(), &value, sizeof value);
      },
      [&](std::size_t k, double e) __attribute__((always_inline)) { g.error[k] = e; });
}
#endif

std::atomic<bool> quartics_baseline_forced{false};

}  // namespace

void cross_dot_quartic_pair(
    const QuadrupleDifferences& q0,
    const QuadrupleDifferences& q1,
    BernsteinQuartic& g0,
    BernsteinQuartic& g1) {
  quartics_body<Lanes>(
      [&](std::size_t k) -> const QuadrupleDifferences& { return k == 0 ? q0 : q1; },
      [&](std::size_t k) -> BernsteinQuartic& { return k == 0 ? g0 : g1; });
}

bool cross_dot_quartics_x4_wide() {
#if defined(SKELCD_QUARTICS_AVX2)
  static const bool kHas = cpu_has_avx2();  // one guard per call, asked on every query
  return kHas && !quartics_baseline_forced.load(std::memory_order_relaxed);
#else
  return false;
#endif
}

void force_baseline_quartics(bool baseline) {
  quartics_baseline_forced.store(baseline, std::memory_order_relaxed);
}

int inside_quadruples(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    QuadrupleDifferences* q) {
  for (int t = 0; t < 2; ++t) {
    const auto& p = t == 0 ? at_t0 : at_t1;
    const auto set = [&](QuadrupleDifferences& x,
                         const Eigen::Vector3d& a,
                         const Eigen::Vector3d& b,
                         const Eigen::Vector3d& c,
                         const Eigen::Vector3d& d) {
      (t == 0 ? x.a_t0 : x.a_t1) = a;
      (t == 0 ? x.b_t0 : x.b_t1) = b;
      (t == 0 ? x.c_t0 : x.c_t1) = c;
      (t == 0 ? x.d_t0 : x.d_t1) = d;
    };
    if (which == InsideQuartics::edge_edge) {
      const Eigen::Vector3d w = *p[2] - *p[0], da = *p[1] - *p[0], db = *p[3] - *p[2];
      set(q[0], w, db, da, db);
      set(q[1], *p[1] - *p[2], db, da, db);
      set(q[2], w, da, da, db);
      set(q[3], da, *p[3] - *p[0], da, db);
    } else {
      const Eigen::Vector3d y = *p[2] - *p[1], z = *p[3] - *p[1];
      set(q[0], y, z, y, *p[0] - *p[1]);
      set(q[1], y, z, *p[3] - *p[2], *p[0] - *p[2]);
      set(q[2], y, z, *p[1] - *p[3], *p[0] - *p[3]);
    }
  }
  if (which == InsideQuartics::edge_edge) return 4;
  q[3] = q[2];
  return 3;
}

int inside_quartic_lanes(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    QuarticLanes& g) {
  assert(cross_dot_quartics_x4_wide());
#if defined(SKELCD_QUARTICS_AVX2)
  if (which == InsideQuartics::edge_edge) {
    inside_quartics_avx2<InsideQuartics::edge_edge>(at_t0, at_t1, g);
    return 4;
  }
  inside_quartics_avx2<InsideQuartics::vertex_face>(at_t0, at_t1, g);
  return 3;
#else
  (void)which;
  (void)at_t0;
  (void)at_t1;
  (void)g;
  return 0;
#endif
}

int inside_quartics_x4(
    InsideQuartics which,
    const std::array<const Eigen::Vector3d*, 4>& at_t0,
    const std::array<const Eigen::Vector3d*, 4>& at_t1,
    BernsteinQuartic* g) {
#if defined(SKELCD_QUARTICS_AVX2)
  if (cross_dot_quartics_x4_wide()) {
    QuarticLanes lanes;
    const int count = inside_quartic_lanes(which, at_t0, at_t1, lanes);
    for (std::size_t k = 0; k < 4; ++k) {
      for (std::size_t i = 0; i < 5; ++i) g[k].coefficients[i] = lanes.coefficients[i][k];
      g[k].error = lanes.error[k];
    }
    return count;
  }
#endif
  // The quadruples, two quartics at a time.
  QuadrupleDifferences q[4];
  const int count = inside_quadruples(which, at_t0, at_t1, q);
  cross_dot_quartic_pair(q[0], q[1], g[0], g[1]);
  cross_dot_quartic_pair(q[2], q[3], g[2], g[3]);
  return count;
}

namespace {

/// algebraic_filter's search with its quartics in groups of W lanes of L (two pairs of two, or
/// one group of four): quartic W p + k in lane k of group p, a group's spare lanes repeating the
/// last quartic and never looked at (not zeros: halving a zero error would make a subnormal
/// product each time, a microcode assist). The nodes, their order and each lane's operations do
/// not depend on the grouping, so neither does the verdict.
template <class L, class B, std::size_t W, std::size_t kGroups, class Quartics>
[[gnu::always_inline]] inline AlgebraicVerdict filter_body(
    const BernsteinCubic& c, const Quartics& g, int count, double toi_tolerance) {
  // Depth first, earlier half first: the left half is processed next, the right half waits.
  using N = Node<L, kGroups>;
  std::array<N, kMaxDepth + 2> waiting;
  int size = 0;
  N node;
  node.lo = 0.0;
  node.hi = 1.0;
  node.depth = 0;
  node.c = c.coefficients;
  node.c_err = c.error;
  constexpr int kWidth = static_cast<int>(W);
  // Groups that hold a quartic (one, with four lanes: the caller has three or four).
  const int groups = kGroups == 1 ? 1 : (count + kWidth - 1) / kWidth;
  if constexpr (std::is_same_v<Quartics, QuarticLanes>) {
    // Already in lanes (lane 3 repeating lane 2 when there are three).
    static_assert(kGroups == 1 && W == 4);
    for (std::size_t k = 0; k < 5; ++k)
      std::memcpy(&node.g[0][k], g.coefficients[k].data(), sizeof(L));
    std::memcpy(&node.g_err[0], g.error.data(), sizeof(L));
  } else {
    for (int i = 0; i < kWidth * groups; ++i) {
      const BernsteinQuartic& q = g[std::min(i, count - 1)];
      const auto p = static_cast<std::size_t>(i / kWidth);
      const auto lane = static_cast<std::size_t>(i % kWidth);
      for (std::size_t k = 0; k < 5; ++k) node.g[p][k][lane] = q.coefficients[k];
      node.g_err[p][lane] = q.error;
    }
  }
  // Lanes that hold a quartic.
  std::array<B, kGroups> used;
  for (std::size_t p = 0; p < kGroups; ++p) {
    for (std::size_t lane = 0; lane < W; ++lane) {
      used[p][lane] = W * p + lane < static_cast<std::size_t>(count) ? ~0ull : 0ull;
    }
  }
  int visited = 0;
  for (;;) {
    // Coplanarity excluded here, or some inside condition failing throughout?
    bool excluded = hull_sign(node.c, node.c_err) != 0;
    bool all_positive = true;
    for (int p = 0; p < groups && !excluded; ++p) {
      const auto pp = static_cast<std::size_t>(p);
      B pos, neg;
      hull_masks(node.g[pp], node.g_err[pp], pos, neg);
      neg &= used[pp];
      pos = pos | ~used[pp];
      if (any_lane(neg)) excluded = true;
      if (!all_lanes(pos)) all_positive = false;
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
    N& right = waiting[static_cast<std::size_t>(size++)];
    right.lo = mid;
    right.hi = node.hi;
    right.depth = node.depth + 1;
    std::array<double, 4> left_c;
    right.c_err = halve(node.c, node.c_err, left_c, right.c);
    node.c = left_c;
    node.c_err = right.c_err;
    for (int p = 0; p < groups; ++p) {
      const auto pp = static_cast<std::size_t>(p);
      std::array<L, 5> left_g;
      right.g_err[pp] = halve(node.g[pp], node.g_err[pp], left_g, right.g[pp]);
      node.g[pp] = left_g;
      node.g_err[pp] = right.g_err[pp];
    }
    node.hi = mid;
    node.depth = right.depth;
  }
  return {AlgebraicOutcome::separated, 1.0, 1.0};
}

#if defined(SKELCD_QUARTICS_AVX2)
/// Three or four quartics in the four lanes of one vector, built for AVX2.
[[gnu::target("avx2")]] AlgebraicVerdict filter_x4_avx2(
    const BernsteinCubic& c, const BernsteinQuartic* g, int count, double toi_tolerance) {
  return filter_body<Lanes4, LaneBits4, 4, 1>(c, g, count, toi_tolerance);
}

/// The same on quartics already in lanes.
[[gnu::target("avx2")]] AlgebraicVerdict filter_lanes_avx2(
    const BernsteinCubic& c, const QuarticLanes& g, int count, double toi_tolerance) {
  return filter_body<Lanes4, LaneBits4, 4, 1>(c, g, count, toi_tolerance);
}
#endif

}  // namespace

AlgebraicVerdict algebraic_filter(
    const BernsteinCubic& c, const BernsteinQuartic* g, int count, double toi_tolerance) {
  assert(count >= 0 && count <= kMaxQuartics);
  // Overflowed bounds (coordinates near the double range) prove nothing: leave it to the solver.
  bool finite = std::isfinite(c.error);
  for (int i = 0; i < count; ++i) finite = finite && std::isfinite(g[i].error);
  if (!finite) return {AlgebraicOutcome::undecided, 0.0, 1.0};
#if defined(SKELCD_QUARTICS_AVX2)
  // Three or four quartics where they come four at once: one vector (half the vector work).
  if (count >= 3 && cross_dot_quartics_x4_wide()) return filter_x4_avx2(c, g, count, toi_tolerance);
#endif
  return filter_body<Lanes, LaneBits, 2, kMaxQuartics / 2>(c, g, count, toi_tolerance);
}

AlgebraicVerdict algebraic_filter_lanes(
    const BernsteinCubic& c, const QuarticLanes& g, int count, double toi_tolerance) {
  assert((count == 3 || count == 4) && cross_dot_quartics_x4_wide());
  bool finite = std::isfinite(c.error);
  for (int i = 0; i < count; ++i)
    finite = finite && std::isfinite(g.error[static_cast<std::size_t>(i)]);
  if (!finite) return {AlgebraicOutcome::undecided, 0.0, 1.0};
#if defined(SKELCD_QUARTICS_AVX2)
  return filter_lanes_avx2(c, g, count, toi_tolerance);
#else
  (void)toi_tolerance;
  return {AlgebraicOutcome::undecided, 0.0, 1.0};
#endif
}

}  // namespace skelcd::ccd::detail
