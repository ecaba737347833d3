// Floating-point expansions (ccd/detail/expansion.hpp) against GMP rationals: the sign of sums and
// products of doubles must be exact, including exact zeros and cancellations far below one ulp of
// the terms, and inputs where a product could leave the exact range must be flagged, not guessed.

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "ccd/detail/expansion.hpp"
#include "ccd/detail/filtered.hpp"
#include "ccd/orientation.hpp"

namespace skelcd::ccd::detail {
namespace {

int rational_sign_of(const mpq_class& q) {
  return mpq_sgn(q.get_mpq_t()) > 0 ? 1 : (mpq_sgn(q.get_mpq_t()) < 0 ? -1 : 0);
}

// orient3d of four points over number type T, as the predicates write it.
template <typename T>
T orient(
    const Eigen::Vector3d& a,
    const Eigen::Vector3d& b,
    const Eigen::Vector3d& c,
    const Eigen::Vector3d& d) {
  const auto pa = lift<T>(a);
  return dot(cross(lift<T>(b) - pa, lift<T>(c) - pa), lift<T>(d) - pa);
}

TEST(Expansion, SignsOfSumsAndProductsAreExact) {
  const Expansion one(1.0);
  const Expansion tiny(0x1p-60);
  // (1 + 2^-60) - 1 - 2^-60 = 0, (1 + 2^-60) - 1 > 0: far below double precision.
  EXPECT_EQ(((one + tiny) - one - tiny).sign(), 0);
  EXPECT_EQ(((one + tiny) - one).sign(), 1);
  EXPECT_EQ((one - (one + tiny)).sign(), -1);
  // (1 + 2^-30)^2 - 1 - 2^-29 = 2^-60 exactly.
  const Expansion x = one + Expansion(0x1p-30);
  EXPECT_EQ((x * x - one - Expansion(0x1p-29) - Expansion(0x1p-60)).sign(), 0);
  EXPECT_EQ((x * x - one - Expansion(0x1p-29)).sign(), 1);
  EXPECT_EQ(Expansion().sign(), 0);
  EXPECT_EQ((Expansion(3.0) * Expansion()).sign(), 0);
  EXPECT_FALSE((x * x).unsafe());
}

TEST(Expansion, OrientationSignsAgreeWithRationals) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> grid(-3, 3);
  std::uniform_int_distribution<int> scale_exp(-40, 40);
  int zeros = 0, nonzeros = 0;
  for (int n = 0; n < 20000; ++n) {
    // Coplanar points on a rotated or scaled grid (exact zeros and near misses after rounding),
    // and generic points nudged by one ulp.
    const double s = std::ldexp(1.0, scale_exp(rng));
    Eigen::Vector3d p[4];
    for (auto& v : p) {
      if (n % 2 == 0) {
        v = s * Eigen::Vector3d(grid(rng), grid(rng), n % 4 == 0 ? 0 : grid(rng)) +
            Eigen::Vector3d(0.1, 0.3, 0.7) * s;
      } else {
        v = s * Eigen::Vector3d(unit(rng), unit(rng), unit(rng));
      }
    }
    if (n % 2 == 1) p[3] = p[0] + (p[1] - p[0]) * 0.5 + (p[2] - p[0]) * 0.25;  // nearly coplanar
    if (n % 3 == 0) {
      double& c = p[n % 4][n % 3];
      c = std::nextafter(c, n % 5 ? 10.0 : -10.0);
    }
    const Expansion e = orient<Expansion>(p[0], p[1], p[2], p[3]);
    ASSERT_FALSE(e.unsafe()) << "case " << n;
    const int expected = rational_sign_of(orient<mpq_class>(p[0], p[1], p[2], p[3]));
    ASSERT_EQ(e.sign(), expected) << "case " << n;
    (expected == 0 ? zeros : nonzeros) += 1;
  }
  EXPECT_GT(zeros, 2000);
  EXPECT_GT(nonzeros, 10000);
}

// The fixed-size triple product (triple_product_sign, which orient3d_exact takes before
// exact_sign) against GMP rationals, on the two kinds of differences it is given: exact ones (one
// component: grid points, coplanar or one ulp off) and rounded ones (two components: points far
// from the origin relative to their spread, nearly coplanar, some exactly so after rounding), and
// on coordinates mixed from 2^-1074 to 2^495 — every sign it gives without raising `unsafe` is
// the rational one, and orient3d_exact's sign is the rational one on every case; and the same for
// the 2-D cross product cross2_sign.
TEST(Expansion, FixedSizeTripleProductIsTheRationalSign) {
  std::mt19937_64 rng(59);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> grid(-3, 3);
  std::uniform_int_distribution<int> scale_exp(-60, 60);
  std::uniform_int_distribution<int> pick(0, 11);
  const int exponents[] = {-1074, -1060, -1022, -700, -540, -401, -100, 0, 100, 300, 495, 0};
  int fixed = 0, zeros = 0, rounded = 0, flagged = 0, crosses = 0;
  for (int n = 0; n < 30000; ++n) {
    const double s = std::ldexp(1.0, scale_exp(rng));
    Eigen::Vector3d p[4];
    const int kind = n % 3;
    for (auto& v : p) {
      if (kind == 0) {
        v = s * Eigen::Vector3d(grid(rng), grid(rng), n % 4 == 0 ? 0 : grid(rng));
      } else if (kind == 1) {
        // Far from the origin relative to the spread: the differences round.
        v = s * (Eigen::Vector3d(1000.0 / 3.0, -700.0 / 7.0, 50.0 / 11.0) +
                 Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
      } else {
        for (int k = 0; k < 3; ++k) {
          v[k] = pick(rng) < 3 ? 0.0 : std::ldexp(unit(rng), exponents[pick(rng)]);
        }
      }
    }
    if (kind == 1 && n % 2 == 0) p[3] = p[0] + (p[1] - p[0]) * 0.5 + (p[2] - p[0]) * 0.25;
    if (kind != 2 && n % 5 == 0) {
      double& c = p[n % 4][n % 3];
      c = std::nextafter(c, n % 7 ? 1e300 : -1e300);
    }
    const int expected = rational_sign_of(orient<mpq_class>(p[0], p[1], p[2], p[3]));
    // orient<T> is (u × v) · w with u = b − a, v = c − a, w = d − a: the product
    // triple_product_sign takes, and det[u; v; w], whose sign orient3d_exact gives.
    Difference u[3], v[3], w[3];
    for (int k = 0; k < 3; ++k) {
      u[k] = difference(p[1][k], p[0][k]);
      v[k] = difference(p[2][k], p[0][k]);
      w[k] = difference(p[3][k], p[0][k]);
      rounded += u[k].n == 2 || v[k].n == 2 || w[k].n == 2;
    }
    bool unsafe = false;
    for (const auto& q : p) {
      for (int k = 0; k < 3; ++k) unsafe = unsafe || expansion_steps::unsafe_leaf(q[k]);
    }
    const int sign = triple_product_sign(u, v, w, unsafe);
    if (unsafe) {
      ++flagged;
    } else {
      ++fixed;
      zeros += expected == 0;
      ASSERT_EQ(sign, expected) << "case " << n;
    }
    ASSERT_EQ(orient3d_exact(p[0], p[1], p[2], p[3]), expected) << "case " << n;
    // The 2-D cross product of the same differences in the plane (x, y) (cross2_sign, which
    // triangles_intersect's coplanar tests take).
    bool unsafe2 = unsafe;
    const int sign2 = cross2_sign(u[0], u[1], v[0], v[1], unsafe2);
    if (!unsafe2) {
      const mpq_class cross2 =
          (mpq_class(p[1].x()) - mpq_class(p[0].x())) *
              (mpq_class(p[2].y()) - mpq_class(p[0].y())) -
          (mpq_class(p[1].y()) - mpq_class(p[0].y())) * (mpq_class(p[2].x()) - mpq_class(p[0].x()));
      ASSERT_EQ(sign2, rational_sign_of(cross2)) << "case " << n;
      ++crosses;
    }
  }
  EXPECT_GT(crosses, 18000);
  EXPECT_GT(fixed, 18000);
  EXPECT_GT(zeros, 2000);
  EXPECT_GT(rounded, 5000);
  EXPECT_GT(flagged, 1000);
}

// orient3d's static filter (ccd/orientation.hpp) on coordinates mixed from the subnormals to
// 2^495 within one query, where products underflow and are multiplied by huge differences: every
// sign it decides is the rational one (it used to take a wrong sign from an underflowed product).
TEST(Expansion, StaticOrient3dFilterIsRightWithUnderflowedProducts) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> pick(0, 11);
  const int exponents[] = {-1074, -1060, -1022, -700, -540, -401, -100, 0, 100, 300, 495, 0};
  int decided = 0;
  for (int n = 0; n < 200000; ++n) {
    Eigen::Vector3d p[4];
    for (auto& v : p) {
      for (int k = 0; k < 3; ++k) {
        const int e = exponents[pick(rng)];
        v[k] = pick(rng) < 3 ? 0.0 : std::ldexp(mantissa(rng), e);
      }
    }
    const int s = orient3d_static(p[0], p[1], p[2], p[3]);
    if (s == kUndecided) continue;
    ++decided;
    // orient3d_static's sign is that of (d − a) · ((b − a) × (c − a)).
    const int expected = rational_sign_of(orient<mpq_class>(p[0], p[1], p[2], p[3]));
    ASSERT_EQ(s, expected) << "case " << n;
  }
  EXPECT_GT(decided, 50000);
}

TEST(Expansion, ProductsNearUnderflowOrOverflowAreFlagged) {
  // Leaves outside [2^-300, 2^300] and products outside the exact range of two-product are flagged,
  // so that exact_sign falls back to rationals.
  EXPECT_TRUE(Expansion(0x1p-400).unsafe());
  EXPECT_TRUE(Expansion(0x1p+400).unsafe());
  EXPECT_TRUE(Expansion(std::nan("")).unsafe());
  const Expansion small(0x1p-290);
  EXPECT_FALSE(small.unsafe());
  EXPECT_TRUE((small * small * small).unsafe());
  const Expansion big(0x1p+290);
  EXPECT_TRUE((big * big * big * big).unsafe());
  // exact_sign still answers them exactly through the rational path.
  EXPECT_EQ(
      exact_sign([]<typename T>() -> T {
        const T a = lift<T>(0x1p-290);
        return T(a * a * a * a - a * a * a * a);
      }),
      0);
  EXPECT_EQ(
      exact_sign([]<typename T>() -> T {
        const T a = lift<T>(0x1p-290);
        return T(a * a * a * a * (lift<T>(1.0) + lift<T>(0x1p-80)) - a * a * a * a);
      }),
      1);
}

// orient3d_exact (ccd/orientation.cpp), the fallback of every DCD filter, against rationals on the
// inputs that reach it on real meshes: flat fans and coplanar grids at mesh scale (exact zeros),
// near-coplanar points nudged by one ulp, the same grids from 2^-200 to 2^200, and coordinates of
// both signs whose differences round. Every path answers here: the axis plane of exact differences
// (the flat fans: a nudge of one ulp off the plane must not be called 0), the dynamic filter and
// the expansion on exact differences (the grids, the generic points) and on the points themselves
// (the differences that round).
TEST(Expansion, ExactOrient3dAgreesWithRationalsOnMeshLikeInputs) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> mesh(0.4, 0.7);  // one sign, within 2x: exact differences
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> grid(-5, 5);
  std::uniform_int_distribution<int> scale_exp(-200, 200);
  int zeros = 0, nonzeros = 0;
  for (int n = 0; n < 40000; ++n) {
    Eigen::Vector3d p[4];
    const int kind = n % 5;
    const double s = std::ldexp(1.0, kind == 3 ? scale_exp(rng) : 0);
    for (auto& v : p) {
      switch (kind) {
        case 0:  // an axis-aligned flat fan at mesh scale: exact zeros through exact differences
          v = Eigen::Vector3d(mesh(rng), mesh(rng), 0.5);
          break;
        case 1:  // coplanar points of a tilted grid at mesh scale
        case 3:  // the same grid scaled by 2^-200 … 2^200
          v = s * (Eigen::Vector3d(0.5, 0.5, 0.5) +
                   0x1p-8 * (grid(rng) * Eigen::Vector3d(1.0, 0.0, 0.25) +
                             grid(rng) * Eigen::Vector3d(0.0, 1.0, -0.5)));
          break;
        case 2:  // generic points at mesh scale
          v = Eigen::Vector3d(mesh(rng), mesh(rng), mesh(rng));
          break;
        default:  // both signs, one near 0: differences that round
          v = Eigen::Vector3d(unit(rng), 1e-9 * unit(rng), unit(rng));
          break;
      }
    }
    if (kind == 2 || kind == 4) p[3] = p[0] + (p[1] - p[0]) * 0.375 + (p[2] - p[0]) * 0.25;
    if (n % 3 == 0) {
      double& c = p[n % 4][(n / 3) % 3];
      c = std::nextafter(c, n % 2 ? 10.0 : -10.0);
    }
    const int expected = rational_sign_of(orient<mpq_class>(p[0], p[1], p[2], p[3]));
    ASSERT_EQ(orient3d_exact(p[0], p[1], p[2], p[3]), expected) << "case " << n;
    // Antisymmetric under an odd permutation, on whichever path that order takes.
    ASSERT_EQ(orient3d_exact(p[1], p[0], p[2], p[3]), -expected) << "case " << n;
    (expected == 0 ? zeros : nonzeros) += 1;
  }
  EXPECT_GT(zeros, 8000);
  EXPECT_GT(nonzeros, 15000);
}

}  // namespace
}  // namespace skelcd::ccd::detail
