// Mixed magnitudes inside one query: the conservative CCD kernels against the exact reference.
//
// The kernel-equivalence and property tests scale each query uniformly. Here one query mixes
// coordinates near 2^-600 with coordinates near 2^500 — per axis (a face that is huge in x and
// tiny in z), per point (a tiny vertex moving through a huge face, a huge vertex through a tiny
// face), and with large translations that leave tiny differences — so that products of tiny
// differences underflow to 0 or a subnormal and are then multiplied by huge ones: the fault the
// triangle-triangle orient3d filter had
// (Expansion.StaticOrient3dFilterIsRightWithUnderflowedProducts). Most queries are contacts built
// on purpose, exactly, so that a wrong "separated" shows up.
//
// Checked on every query, against GMP rationals:
//  * the whole kernel: no false negative; toi_lower <= the exact first contact; a contact the
//    algebraic filter certified is a contact at the time it certified;
//  * each stage on its own (the same inputs as ccd/vertex_face.cpp and ccd/edge_edge.cpp build):
//    every Bernstein coefficient of the coplanarity cubic and of the inside quartics within its
//    stated error bound (the screen's and the exact one); the normal bound above every |n(t)|;
//    the coplanarity filter, the algebraic filter and the inclusion solver (from t = 0) never
//    excluding a contact, and their certified contacts real.

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <string_view>

#include "ccd/detail/algebraic_filter.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/inclusion_solver.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/filters.hpp"
#include "ccd/vertex_face.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

using test::RandomQuery;
using V = Eigen::Vector3d;
using ExactVector = std::array<mpq_class, 3>;  // rational points of the generator

// ---- Queries ----

// Point indices of RandomQuery::points: vertex-face v, f0, f1, f2; edge-edge a0, a1, b0, b1; the
// same four at t = 1 at index + 4.
constexpr int kT1 = 4;
// The solver-alone check's budget (the kernel's is 10^6): enough to separate what the filters
// separate on these queries, and an iteration-limit stop only ever says "hit".
constexpr std::int64_t kSolverBoxes = 1000;

// Exponent bands of the per-axis and per-point scales: near the bottom of the tested range, near
// its top, and in between.
int band_exponent(std::mt19937_64& rng) {
  static constexpr std::array<std::array<int, 2>, 5> kBands = {
      {{-600, -520}, {-560, -400}, {-40, 40}, {300, 440}, {440, 500}}};
  const auto& b = kBands[std::uniform_int_distribution<std::size_t>(0, kBands.size() - 1)(rng)];
  return std::uniform_int_distribution<int>(b[0], b[1])(rng);
}

// A time of contact t* = 2^-m (or 1 - 2^-m), m in 0..4, so that a point of a linear motion can be
// solved from the other end and t* exactly, in doubles, on a small dyadic grid.
struct ContactTime {
  int m = 1;
  bool from_end = false;  // t* = 1 - 2^-m: the t = 1 end is free, the t = 0 end is solved
};

// x(t*) for x moving from x_t0 to x_t1 (exact on the grids used here).
V at(const ContactTime& tc, const V& x_t0, const V& x_t1) {
  const double h = std::ldexp(1.0, -tc.m);
  return tc.from_end ? V(x_t1 + (x_t0 - x_t1) * h) : V(x_t0 + (x_t1 - x_t0) * h);
}

// Makes x(t*) = target by solving the end that is not free: x_t1 = 2^m target - (2^m - 1) x_t0,
// or the mirror image.
void pass_through(const ContactTime& tc, const V& target, V& x_t0, V& x_t1) {
  const double k = std::ldexp(1.0, tc.m);
  if (tc.from_end) {
    x_t0 = k * target - (k - 1.0) * x_t1;
  } else {
    x_t1 = k * target - (k - 1.0) * x_t0;
  }
}

class MixedMagnitudeGenerator {
 public:
  explicit MixedMagnitudeGenerator(std::uint64_t seed) : rng_(seed), property_(seed + 1) {}

  // The next query and whether it is a contact by construction (exactly, in doubles).
  RandomQuery next(bool& built_contact) {
    built_contact = false;
    // Shares: 5/16 grid contacts, 6/16 tiny near huge, 1/16 rounded contacts (the exact
    // reference takes about 20 ms on each of those), 4/16 the property mix with scaled axes.
    switch (integer(0, 15)) {
      case 0:
      case 1:
      case 2:
      case 3:
      case 4: {
        RandomQuery q = grid_contact();
        built_contact = !nudge(q);
        scale_axes(q, true);
        return q;
      }
      case 5:
      case 6:
      case 7:
      case 8:
      case 9:
      case 10: {
        RandomQuery q = tiny_near_huge();
        built_contact = !q.kind.ends_with("offset") && !nudge_ulp(q);
        return q;
      }
      case 11:
        return rounded_contact();
      default: {
        // The property mix (near-degenerate, nudged contacts), then each axis scaled by its own
        // power of two when that is exact.
        RandomQuery q = property_.next();
        q.kind = "property, axes scaled";
        scale_axes(q, false);
        return q;
      }
    }
  }

 private:
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool one_in(int n) { return integer(0, n - 1) == 0; }
  V grid(int r) {
    const auto x = static_cast<double>(integer(-r, r));
    const auto y = static_cast<double>(integer(-r, r));
    return {x, y, static_cast<double>(integer(-r, r))};
  }
  ContactTime contact_time() { return {integer(0, 4), one_in(2)}; }

  // A contact on an integer grid with dyadic weights: exact in doubles. Often on an edge or a
  // corner of the triangle or at an end of a segment, sometimes with a still or degenerate
  // primitive.
  RandomQuery grid_contact() {
    constexpr int kR = 1024;
    RandomQuery q;
    q.vertex_face = one_in(2);
    auto& p = q.points;
    for (auto& x : p) x = grid(kR);
    if (one_in(4)) {
      for (int i = 1; i < 4; ++i)
        p[static_cast<std::size_t>(i + kT1)] = p[static_cast<std::size_t>(i)];
    }
    const ContactTime tc = contact_time();
    if (q.vertex_face) {
      q.kind = "grid contact vf";
      if (one_in(8)) {
        // Zero-area triangle: f2 = 2 f1 - f0 at both times.
        p[3] = 2 * p[2] - p[1];
        p[7] = 2 * p[6] - p[5];
      }
      int w0 = integer(0, 8), w1 = integer(0, 8 - w0);
      if (one_in(3)) w0 = 0;
      const int w2 = 8 - w0 - w1;
      const V target =
          (w0 * at(tc, p[1], p[5]) + w1 * at(tc, p[2], p[6]) + w2 * at(tc, p[3], p[7])) / 8.0;
      pass_through(tc, target, p[0], p[4]);
    } else {
      q.kind = "grid contact ee";
      // A point of edge a at t*, then edge b's end b1 placed so that b passes through it.
      const double alpha = integer(0, 8) / 8.0;
      const V a0 = at(tc, p[0], p[4]), a1 = at(tc, p[1], p[5]);
      const V x = a0 + alpha * (a1 - a0);
      const V b0 = at(tc, p[2], p[6]);
      const V b1 = b0 + (x - b0) * std::ldexp(1.0, integer(0, 3));  // beta = 2^-j
      pass_through(tc, b1, p[3], p[7]);
    }
    return q;
  }

  // Each axis scaled by its own power of two, often translated by a large multiple of its grid
  // step first. Exact (checked; the query is left as it was when it would not be), so a contact
  // stays a contact: the map is affine.
  void scale_axes(RandomQuery& q, bool translate) {
    std::array<int, 3> exponents;
    for (int& e : exponents) e = band_exponent(rng_);
    if (one_in(3)) {
      // One huge axis and two tiny ones whose 2 x 2 minors underflow (2^-1080 and below) while
      // the other terms of the determinants do not: then a lost minor times a huge difference is
      // as large as the whole determinant — the orient3d filter's fault.
      const int huge = integer(0, 2);
      for (int k = 0; k < 3; ++k) {
        exponents[static_cast<std::size_t>(k)] =
            k == huge ? integer(440, 500) : integer(-600, -540);
      }
    }
    if (one_in(6)) {
      // One axis down at the subnormal boundary, where even the solver's u E products (u >= 2^-60)
      // underflow; the scaling is left out below if it would round.
      exponents[static_cast<std::size_t>(integer(0, 2))] = integer(-1060, -990);
    }
    for (int k = 0; k < 3; ++k) {
      const int e = exponents[static_cast<std::size_t>(k)];
      const double shift = translate && one_in(2)
                               ? (one_in(2) ? 1.0 : -1.0) * std::ldexp(1.0, integer(11, 30))
                               : 0.0;
      std::array<double, 8> mapped;
      bool exact = true;
      for (std::size_t i = 0; i < 8; ++i) {
        const double x = q.points[i][k];
        mapped[i] = std::ldexp(x + shift, e);
        exact = exact && std::isfinite(mapped[i]) && std::ldexp(mapped[i], -e) - shift == x;
      }
      if (!exact) continue;
      for (std::size_t i = 0; i < 8; ++i) q.points[i][k] = mapped[i];
    }
  }

  // Sometimes moves one coordinate by one grid step (before scaling) or by a fraction of one:
  // contacts become near misses or stay contacts; the exact reference decides. True if it did.
  bool nudge(RandomQuery& q) {
    if (!one_in(3)) return false;
    const auto i = static_cast<std::size_t>(integer(0, 7));
    const int k = integer(0, 2);
    q.points[i][k] += (one_in(2) ? 1.0 : -1.0) * std::ldexp(1.0, -integer(0, 12));
    q.kind = q.vertex_face ? "grid contact vf, nudged" : "grid contact ee, nudged";
    return true;
  }

  // Sometimes moves one coordinate by one ulp. True if it did.
  bool nudge_ulp(RandomQuery& q) {
    if (!one_in(4)) return false;
    auto& x = q.points[static_cast<std::size_t>(integer(0, 7))][integer(0, 2)];
    x = std::nextafter(x, one_in(2) ? HUGE_VAL : -HUGE_VAL);
    return true;
  }

  // A huge primitive through the origin and a tiny one through the origin at t* (or the other
  // way round), so that they touch at the origin: exact in doubles. The huge one touches at an
  // interior point, an edge or a corner; the tiny one sometimes misses the origin by a tinier
  // offset ("offset": the exact reference decides).
  RandomQuery tiny_near_huge() {
    RandomQuery q;
    q.vertex_face = one_in(2);
    auto& p = q.points;
    const bool face_huge = one_in(2);  // vertex-face: the face is the huge one; edge-edge: b
    const int huge = integer(300, 500);
    const int tiny = integer(-600, -400);
    const ContactTime tc = contact_time();
    const bool still = one_in(2);
    if (q.vertex_face) {
      const double fs = std::ldexp(1.0, face_huge ? huge : tiny);
      const double vs = std::ldexp(1.0, face_huge ? tiny : huge);
      // The origin as the triangle's centroid, the midpoint of its edge f0 f1, or its corner f0,
      // at every time.
      const int where = integer(0, 2);
      for (int t = 0; t < 2; ++t) {
        const auto o = static_cast<std::size_t>(t * kT1);
        if (t == 1 && still) {
          for (std::size_t i = 1; i < 4; ++i) p[i + kT1] = p[i];
          break;
        }
        p[o + 1] = grid(1024) * fs;
        p[o + 2] = grid(1024) * fs;
        p[o + 3] = grid(1024) * fs;
        if (where == 0) p[o + 3] = -(p[o + 1] + p[o + 2]);
        if (where == 1) p[o + 2] = -p[o + 1];
        if (where == 2) p[o + 1] = V::Zero();
      }
      q.kind = face_huge ? "tiny vertex, huge face" : "huge vertex, tiny face";
      p[0] = grid(1024) * vs;
      p[4] = grid(1024) * vs;
      V target = V::Zero();
      if (one_in(4)) {
        target = grid(4) * std::ldexp(std::min(fs, vs), -integer(0, 20));
        q.kind = face_huge ? "tiny vertex, huge face, offset" : "huge vertex, tiny face, offset";
      }
      pass_through(tc, target, p[0], p[4]);
    } else {
      const double as = std::ldexp(1.0, face_huge ? tiny : huge);
      const double bs = std::ldexp(1.0, face_huge ? huge : tiny);
      q.kind = face_huge ? "tiny edge a, huge edge b" : "huge edge a, tiny edge b";
      // Edge b through the origin at every time: b0 = -g, b1 = k g (or b0 = 0, an end), with the
      // same k at both ends of the motion (so that b1(t) = -k b0(t) at every t).
      const bool end_at_origin = one_in(4);
      const double k = integer(1, 3);
      for (int t = 0; t < 2; ++t) {
        const auto o = static_cast<std::size_t>(t * kT1);
        if (t == 1 && still) {
          p[2 + kT1] = p[2];
          p[3 + kT1] = p[3];
          break;
        }
        const V g = grid(1024) * bs;
        p[o + 2] = end_at_origin ? V::Zero() : V(-g);
        p[o + 3] = k * g;
      }
      // Edge a through the origin (or a point near it) at t*.
      const V dir = grid(1024) * as;
      const V a0 = one_in(4) ? V::Zero() : V(-dir);
      V a1 = integer(1, 3) * dir;
      if (one_in(4)) {
        a1 += grid(4) * std::ldexp(std::min(as, bs), -integer(0, 20));
        q.kind =
            face_huge ? "tiny edge a, huge edge b, offset" : "huge edge a, tiny edge b, offset";
      }
      p[0] = grid(1024) * as;
      p[1] = grid(1024) * as;
      p[4] = grid(1024) * as;
      p[5] = grid(1024) * as;
      pass_through(tc, a0, p[0], p[4]);
      pass_through(tc, a1, p[1], p[5]);
    }
    return q;
  }

  // Every point at its own scale; a contact built in rationals at some time and place, then
  // the solved point rounded to the nearest double: within rounding of contact, either way.
  RandomQuery rounded_contact() {
    RandomQuery q;
    q.vertex_face = one_in(2);
    q.kind = q.vertex_face ? "rounded contact vf" : "rounded contact ee";
    for (std::size_t i = 0; i < 4; ++i) {
      const int e = band_exponent(rng_);
      q.points[i] = grid(1024) * std::ldexp(1.0, e);
      q.points[i + kT1] = grid(1024) * std::ldexp(1.0, one_in(2) ? e : band_exponent(rng_));
    }
    // A short dyadic time: the exact reference's cost grows with the bits of the input, and the
    // rounded point has 53 of them anyway.
    const mpq_class t(integer(0, 1024), 1024);
    const auto exact_at = [&](std::size_t i) {
      ExactVector x;
      for (int k = 0; k < 3; ++k) {
        x[static_cast<std::size_t>(k)] =
            (1 - t) * mpq_class(q.points[i][k]) + t * mpq_class(q.points[i + kT1][k]);
      }
      return x;
    };
    // The exact position of the solved point at t*, then its t = 1 end.
    ExactVector target;
    std::size_t solved = 0;
    if (q.vertex_face) {
      const mpq_class w0(integer(0, 64), 64);
      const mpq_class w1(integer(0, 64 - static_cast<int>(w0.get_num().get_si())), 64);
      const ExactVector f0 = exact_at(1), f1 = exact_at(2), f2 = exact_at(3);
      for (std::size_t k = 0; k < 3; ++k)
        target[k] = w0 * f0[k] + w1 * f1[k] + (1 - w0 - w1) * f2[k];
    } else {
      const mpq_class alpha(integer(0, 64), 64);
      const mpq_class beta(integer(1, 64), 64);
      const ExactVector a0 = exact_at(0), a1 = exact_at(1), b0 = exact_at(2);
      for (std::size_t k = 0; k < 3; ++k) {
        const mpq_class x = a0[k] + alpha * (a1[k] - a0[k]);
        target[k] = b0[k] + (x - b0[k]) / beta;
      }
      solved = 3;
    }
    if (t == 0) return q;  // nothing to solve for; an ordinary query
    for (int k = 0; k < 3; ++k) {
      const mpq_class end =
          (target[static_cast<std::size_t>(k)] - (1 - t) * mpq_class(q.points[solved][k])) / t;
      q.points[solved + kT1][k] = round_to_nearest(end);
    }
    return q;
  }

  std::mt19937_64 rng_;
  test::RandomQueryGenerator property_;
};

// ---- The stages' inputs, as ccd/vertex_face.cpp and ccd/edge_edge.cpp build them ----

// A difference points[from] - points[to] of the query, one floating-point subtraction in the
// kernels, exact here.
struct Difference {
  int from, to;
};

// c(t) = X . (Y x Z): vertex-face X = v - f0, Y = f1 - f0, Z = f2 - f0; edge-edge X = b0 - a0,
// Y = a1 - a0, Z = b1 - b0.
constexpr std::array<Difference, 3> kCoplanarityVf = {{{0, 1}, {2, 1}, {3, 1}}};
constexpr std::array<Difference, 3> kCoplanarityEe = {{{2, 0}, {1, 0}, {3, 2}}};
// The inside quartics (A x B) . (C x D).
constexpr std::array<std::array<Difference, 4>, 3> kQuarticsVf = {{
    {{{2, 1}, {3, 1}, {2, 1}, {0, 1}}},
    {{{2, 1}, {3, 1}, {3, 2}, {0, 2}}},
    {{{2, 1}, {3, 1}, {1, 3}, {0, 3}}},
}};
constexpr std::array<std::array<Difference, 4>, 4> kQuarticsEe = {{
    {{{2, 0}, {3, 2}, {1, 0}, {3, 2}}},
    {{{1, 2}, {3, 2}, {1, 0}, {3, 2}}},
    {{{2, 0}, {1, 0}, {1, 0}, {3, 2}}},
    {{{1, 0}, {3, 0}, {1, 0}, {3, 2}}},
}};
// The solver's F = D + u E + v G: vertex-face D = v - f0, E = f0 - f1, G = f0 - f2; edge-edge
// D = a0 - b0, E = a1 - a0, G = b0 - b1.
constexpr std::array<Difference, 3> kSolverVf = {{{0, 1}, {1, 2}, {1, 3}}};
constexpr std::array<Difference, 3> kSolverEe = {{{0, 2}, {1, 0}, {2, 3}}};

V rounded(const RandomQuery& q, Difference d, int t) {
  return q.points[static_cast<std::size_t>(d.from + t * kT1)] -
         q.points[static_cast<std::size_t>(d.to + t * kT1)];
}

// The query's coordinates as integers: every finite double is an integer multiple of 2^-shift for
// shift = 1074, and of a coarser power for the query at hand. Integers keep GMP off gcds of
// 2000-bit denominators; a product of d coordinates is then scaled by 2^(d shift).
using IntegerVector = std::array<mpz_class, 3>;

struct IntegerQuery {
  int shift = 0;
  std::array<IntegerVector, 8> points;
};

IntegerQuery integers(const RandomQuery& q) {
  IntegerQuery out;
  for (const V& p : q.points) {
    for (int k = 0; k < 3; ++k) {
      int e = 0;
      if (p[k] != 0.0) std::frexp(p[k], &e);  // |x| < 2^e, a multiple of 2^(e - 53) (or of 2^-1074)
      out.shift = std::max(out.shift, std::min(53 - e, 1074));
    }
  }
  for (std::size_t i = 0; i < 8; ++i) {
    for (std::size_t k = 0; k < 3; ++k) {
      mpq_class x(q.points[i][static_cast<int>(k)]);
      mpq_mul_2exp(x.get_mpq_t(), x.get_mpq_t(), static_cast<mp_bitcnt_t>(out.shift));
      out.points[i][k] = x.get_num();  // the denominator is 1 now
    }
  }
  return out;
}

IntegerVector exact(const IntegerQuery& q, Difference d, unsigned t) {
  const auto& a = q.points[static_cast<std::size_t>(d.from) + t * kT1];
  const auto& b = q.points[static_cast<std::size_t>(d.to) + t * kT1];
  return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}

IntegerVector cross(const IntegerVector& a, const IntegerVector& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

mpz_class dot(const IntegerVector& a, const IntegerVector& b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// The exact Bernstein coefficients of a product of N linear factors are its blossom: b_i is the
// average of the C(N, i) evaluations with i of the factors at t = 1. Here the sums, and the count.
template <std::size_t N>
struct Blossom {
  std::array<mpz_class, N + 1> sum;
  std::array<int, N + 1> terms{};
};

template <std::size_t N, typename Evaluate>
Blossom<N> blossom(Evaluate&& evaluate) {
  Blossom<N> b;
  for (unsigned mask = 0; mask < (1u << N); ++mask) {
    const auto level = static_cast<std::size_t>(std::popcount(mask));
    b.sum[level] += evaluate(mask);
    ++b.terms[level];
  }
  return b;
}

// Every computed coefficient within `error` of the exact one, sum_i / (terms_i 2^(N shift)).
template <std::size_t N>
::testing::AssertionResult within(
    const std::array<double, N + 1>& computed,
    double error,
    const Blossom<N>& exact_coefficients,
    int shift) {
  if (!std::isfinite(error))
    return ::testing::AssertionSuccess();  // proves nothing, claims nothing
  const auto scale = static_cast<mp_bitcnt_t>(static_cast<int>(N) * shift);
  for (std::size_t i = 0; i <= N; ++i) {
    if (!std::isfinite(computed[i])) {
      return ::testing::AssertionFailure()
             << "coefficient " << i << " is " << computed[i] << " with a finite bound " << error;
    }
    // |computed - exact| <= error, both sides times terms_i 2^(N shift).
    mpq_class off = mpq_class(computed[i]) * exact_coefficients.terms[i];
    mpq_mul_2exp(off.get_mpq_t(), off.get_mpq_t(), scale);
    off = abs(off - exact_coefficients.sum[i]);
    mpq_class allowed = mpq_class(error) * exact_coefficients.terms[i];
    mpq_mul_2exp(allowed.get_mpq_t(), allowed.get_mpq_t(), scale);
    if (off > allowed) {
      mpq_class exact_value(exact_coefficients.sum[i], exact_coefficients.terms[i]);
      mpq_div_2exp(exact_value.get_mpq_t(), exact_value.get_mpq_t(), scale);
      return ::testing::AssertionFailure()
             << "coefficient " << i << " is " << computed[i] << ", exactly " << exact_value.get_d()
             << ", beyond the bound " << error;
    }
  }
  return ::testing::AssertionSuccess();
}

// What the exact reference says, with a narrow bracket for comparing times.
struct Truth {
  bool hit = false;
  mpq_class lo, hi;
};

Truth exact_answer(const RandomQuery& q) {
  const mpq_class width(1, 1 << 20);
  const ExactCcdResult e = q.vertex_face ? vertex_face_ccd_rational(to_rational(q.vf()), width)
                                         : edge_edge_ccd_rational(to_rational(q.ee()), width);
  return {e.hit, e.toi_lo, e.toi_hi};
}

std::string describe(const RandomQuery& q) {
  std::ostringstream s;
  s.precision(17);
  s << (q.vertex_face ? "vf" : "ee") << " (" << q.kind << "):";
  for (const V& p : q.points)
    s << " " << std::hexfloat << p[0] << " " << p[1] << " " << p[2] << ";";
  return s.str();
}

struct Tally {
  int queries = 0, contacts = 0, built = 0, false_negatives = 0, wrong_certificates = 0;
  int coplanarity_certified = 0, algebraic_decided = 0, solver_separated = 0;
  std::map<std::string_view, std::array<int, 2>> kinds;  // queries, exact contacts
};

// Checks one query, whole kernel and stage by stage; counts into `tally`.
void check(const RandomQuery& q, bool built_contact, int index, Tally& tally) {
  const std::string what = describe(q);
  const Truth truth = exact_answer(q);
  ++tally.queries;
  auto& kind = tally.kinds[q.kind];
  ++kind[0];
  if (truth.hit) {
    ++tally.contacts;
    ++kind[1];
  }
  if (built_contact) {
    ++tally.built;
    EXPECT_TRUE(truth.hit) << "built as a contact: " << what;
  }
  // A certified contact in [lo, hi] must be one: the exact first contact is there or earlier, and
  // it is not before lo (a certified contact's lo is a lower bound too).
  const auto certified_contact_is_right = [&](double lo, double hi, const char* stage) {
    const bool right = truth.hit && mpq_class(lo) <= truth.hi && truth.lo <= mpq_class(hi);
    if (!right) ++tally.wrong_certificates;
    EXPECT_TRUE(right) << stage << " certified a contact in [" << lo << ", " << hi << "]: " << what;
  };
  const auto exclusion_is_right = [&](bool excluded, const char* stage) {
    if (excluded && truth.hit) ++tally.wrong_certificates;
    EXPECT_FALSE(excluded && truth.hit) << stage << " excluded a contact: " << what;
  };

  // The whole kernel.
  CcdStats stats;
  const CcdResult c = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, {}, stats)
                                    : edge_edge_ccd(q.ee(), Accuracy::conservative, {}, stats);
  if (truth.hit && !c.hit) {
    ++tally.false_negatives;
    ADD_FAILURE() << "false negative: " << what;
  }
  if (truth.hit && c.hit) {
    EXPECT_LE(mpq_class(c.toi_lower), truth.hi) << "toi_lower after the first contact: " << what;
  }
  if (stats.algebraic_hits > 0) certified_contact_is_right(c.toi_lower, c.toi_upper, "kernel");
  if (truth.hit) {
    // A contact is within any distance of contact.
    CcdOptions options;
    options.min_separation = std::ldexp(1.0, (index * 37) % 1100 - 600);
    const CcdResult cs = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, options)
                                       : edge_edge_ccd(q.ee(), Accuracy::conservative, options);
    EXPECT_TRUE(cs.hit) << "missed with min_separation " << options.min_separation << ": " << what;
  }

  // Stage 1, the coplanarity cubic: every coefficient within the screen's bound and the exact
  // bound; a certified sign excludes no contact.
  const IntegerQuery iq = integers(q);
  const auto& coplanarity = q.vertex_face ? kCoplanarityVf : kCoplanarityEe;
  detail::DifferenceTriple d[2];
  std::array<std::array<IntegerVector, 3>, 2> xyz;  // [time][X, Y, Z]
  for (unsigned t = 0; t < 2; ++t) {
    const auto it = static_cast<int>(t);
    d[t] = {
        rounded(q, coplanarity[0], it),
        rounded(q, coplanarity[1], it),
        rounded(q, coplanarity[2], it)};
    for (std::size_t j = 0; j < 3; ++j) xyz[t][j] = exact(iq, coplanarity[j], t);
  }
  const auto cubic = blossom<3>([&](unsigned mask) {
    return dot(xyz[mask & 1][0], cross(xyz[(mask >> 1) & 1][1], xyz[(mask >> 2) & 1][2]));
  });
  const detail::TrilinearScreen screen = detail::trilinear_screen(d[0], d[1]);
  EXPECT_TRUE(within<3>(screen.coefficients, screen.error_upper, cubic, iq.shift))
      << "screen: " << what;
  EXPECT_TRUE(within<3>(screen.coefficients, detail::trilinear_error(d[0], d[1]), cubic, iq.shift))
      << "cubic: " << what;
  const bool screened = detail::certified_sign(screen.coefficients, screen.error_upper);
  exclusion_is_right(screened, "the coplanarity screen");
  const bool coplanarity_rejects =
      q.vertex_face ? coplanarity_filter_rejects(q.vf()) : coplanarity_filter_rejects(q.ee());
  exclusion_is_right(coplanarity_rejects, "the coplanarity filter");
  if (coplanarity_rejects) ++tally.coplanarity_certified;
  // |n(t)| <= sum_k max_i |N_ik| for the Bernstein coefficients N_i of n = Y x Z.
  {
    const auto& [x0, y0, z0] = xyz[0];
    const auto& [x1, y1, z1] = xyz[1];
    const IntegerVector n0 = cross(y0, z0), n2 = cross(y1, z1);
    const IntegerVector a = cross(y0, z1), b = cross(y1, z0);
    mpz_class twice_bound = 0;  // times 2^(2 shift)
    for (std::size_t k = 0; k < 3; ++k) {
      const mpz_class n1 = a[k] + b[k];
      const mpz_class m0 = 2 * abs(n0[k]), m1 = abs(n1), m2 = 2 * abs(n2[k]);
      twice_bound += std::max({m0, m1, m2});
    }
    const double computed = detail::cross_norm_bound(d[0], d[1]);
    if (std::isfinite(computed)) {
      mpq_class scaled = 2 * mpq_class(computed);
      mpq_mul_2exp(scaled.get_mpq_t(), scaled.get_mpq_t(), static_cast<mp_bitcnt_t>(2 * iq.shift));
      EXPECT_GE(scaled, twice_bound) << "normal bound: " << what;
    }
  }

  // Stage 2, the inside quartics, one by one and in pairs, and the algebraic filter on its own.
  const int count = q.vertex_face ? 3 : 4;
  std::array<detail::QuadrupleDifferences, 4> inputs;
  std::array<detail::BernsteinQuartic, 4> g;
  std::array<Blossom<4>, 4> g_exact;
  bool finite = true;
  for (int i = 0; i < count; ++i) {
    const auto ii = static_cast<std::size_t>(i);
    const auto& f = q.vertex_face ? kQuarticsVf[ii] : kQuarticsEe[ii];
    inputs[ii] = {
        rounded(q, f[0], 0),
        rounded(q, f[1], 0),
        rounded(q, f[2], 0),
        rounded(q, f[3], 0),
        rounded(q, f[0], 1),
        rounded(q, f[1], 1),
        rounded(q, f[2], 1),
        rounded(q, f[3], 1)};
    for (int t = 0; t < 2; ++t) {
      for (const Difference& x : f) finite = finite && rounded(q, x, t).allFinite();
    }
    g_exact[ii] = blossom<4>([&](unsigned mask) {
      return dot(
          cross(exact(iq, f[0], mask & 1), exact(iq, f[1], (mask >> 1) & 1)),
          cross(exact(iq, f[2], (mask >> 2) & 1), exact(iq, f[3], (mask >> 3) & 1)));
    });
    g[ii] = detail::cross_dot_quartic(inputs[ii]);
    EXPECT_TRUE(within<4>(g[ii].coefficients, g[ii].error, g_exact[ii], iq.shift))
        << "quartic " << i << ": " << what;
  }
  if (finite) {
    for (int i = 0; i + 1 < count; i += 2) {
      const auto ii = static_cast<std::size_t>(i);
      detail::BernsteinQuartic p0, p1;
      detail::cross_dot_quartic_pair(inputs[ii], inputs[ii + 1], p0, p1);
      EXPECT_TRUE(within<4>(p0.coefficients, p0.error, g_exact[ii], iq.shift))
          << "pair " << i << ": " << what;
      EXPECT_TRUE(within<4>(p1.coefficients, p1.error, g_exact[ii + 1], iq.shift))
          << "pair " << i + 1 << ": " << what;
    }
  }
  const detail::AlgebraicVerdict verdict =
      detail::algebraic_filter(detail::trilinear_determinant(d[0], d[1]), g.data(), count, 1e-6);
  switch (verdict.outcome) {
    case detail::AlgebraicOutcome::separated:
      ++tally.algebraic_decided;
      exclusion_is_right(true, "the algebraic filter");
      break;
    case detail::AlgebraicOutcome::contact:
      ++tally.algebraic_decided;
      certified_contact_is_right(verdict.t_lo, verdict.t_hi, "the algebraic filter");
      break;
    case detail::AlgebraicOutcome::undecided:
      if (truth.hit) {
        EXPECT_LE(mpq_class(verdict.t_lo), truth.hi) << "algebraic filter: " << what;
      }
      break;
  }

  // Stage 3, the inclusion solver on its own, from t = 0.
  const auto& solver = q.vertex_face ? kSolverVf : kSolverEe;
  detail::InclusionProblem problem;
  problem.d_t0 = rounded(q, solver[0], 0);
  problem.e_t0 = rounded(q, solver[1], 0);
  problem.g_t0 = rounded(q, solver[2], 0);
  problem.d_t1 = rounded(q, solver[0], 1);
  problem.e_t1 = rounded(q, solver[1], 1);
  problem.g_t1 = rounded(q, solver[2], 1);
  problem.triangle_domain = q.vertex_face;
  CcdOptions solver_options;
  solver_options.max_iterations = kSolverBoxes;
  const detail::InclusionResult r = detail::solve_inclusion(problem, solver_options);
  if (!r.hit) {
    ++tally.solver_separated;
    exclusion_is_right(true, "the inclusion solver");
  } else if (truth.hit) {
    EXPECT_LE(mpq_class(r.toi_lower), truth.hi) << "solver's toi_lower: " << what;
  }
}

constexpr int kQueries = 1800;

TEST(MixedMagnitude, ConservativeNeverMissesAContactAndCertifiesOnlyTruths) {
  MixedMagnitudeGenerator gen(20250101);
  Tally tally;
  for (int i = 0; i < kQueries; ++i) {
    bool built = false;
    const RandomQuery q = gen.next(built);
    check(q, built, i, tally);
  }
  EXPECT_EQ(tally.false_negatives, 0);
  EXPECT_EQ(tally.wrong_certificates, 0);
  for (const auto& [kind, k] : tally.kinds) {
    std::cout << "  " << kind << ": " << k[0] << " queries, " << k[1] << " exact contacts\n";
  }
  std::cout << "  " << tally.contacts << " contacts (" << tally.built
            << " built exactly); decided: " << tally.coplanarity_certified
            << " by the coplanarity filter, " << tally.algebraic_decided
            << " by the algebraic filter alone, " << tally.solver_separated
            << " separated by the solver alone\n";
  // The mix must be testing something: mostly contacts, and every stage deciding some queries.
  EXPECT_GT(tally.contacts, kQueries / 2);
  EXPECT_GT(tally.coplanarity_certified, kQueries / 200);
  EXPECT_GT(tally.algebraic_decided, kQueries / 20);
  EXPECT_GT(tally.solver_separated, kQueries / 50);
}

}  // namespace
}  // namespace skelcd::ccd
