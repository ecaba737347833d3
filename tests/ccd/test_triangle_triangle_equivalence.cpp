// ccd::triangles_intersect against the implementation it replaced (issue 14), kept verbatim in
// tests/ccd/triangle_triangle_reference.cpp: the same boolean on every query — uniform random
// triangles; grid triangles (exact coplanarity, collinearity, touching at a point or along an
// edge, zero-area triangles, coincident corners); contacts built exactly and then nudged by a few
// ulps; every SharedCorners pattern; each query also with the triangles swapped and scaled by
// powers of two from 2^-1000 to 2^300. Patterns that name a corner of b twice are judged by the
// brute force (tests/ccd/triangle_triangle_brute.cpp) instead: there the old code was wrong. The
// real queries of posed frames are in tests/culling/test_triangle_triangle_real.cpp (they need the
// model loaders).
//
// Non-finite coordinates are not tested: neither implementation defines an answer for them (the
// exact fallback converts to GMP rationals, which has none), and positions are checked for
// finiteness once per frame where they enter (skinning/).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cassert>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "ccd/orientation.hpp"
#include "ccd/triangle_triangle.hpp"
#include "tests/ccd/triangle_triangle_brute.hpp"
#include "tests/ccd/triangle_triangle_reference.hpp"

namespace skelcd::ccd {
namespace {

using reference::triangles_intersect_reference;
using V = Eigen::Vector3d;

// Every SharedCorners a pair can have: each of a's corners mapped to one of b's or to none (4^3 =
// 64). Two of a's corners mapped to the same corner of b are one mesh vertex repeated by a
// degenerate triangle (the DCD hands such pairs over: RobotExpressive has them); apply_shared
// then gives them one position.
std::vector<SharedCorners> all_shared_patterns() {
  std::vector<SharedCorners> out;
  for (int m0 = -1; m0 < 3; ++m0) {
    for (int m1 = -1; m1 < 3; ++m1) {
      for (int m2 = -1; m2 < 3; ++m2) {
        out.push_back(
            {static_cast<std::int8_t>(m0),
             static_cast<std::int8_t>(m1),
             static_cast<std::int8_t>(m2)});
      }
    }
  }
  return out;
}

bool injective(const SharedCorners& shared) {
  return (shared[0] < 0 || (shared[0] != shared[1] && shared[0] != shared[2])) &&
         (shared[1] < 0 || shared[1] != shared[2]);
}

// Gives b's shared corners the positions of a's (and a's corners shared with the same corner of b
// one position).
void apply_shared(TriangleTriangleQuery& q, const SharedCorners& shared) {
  V* a[3] = {&q.a0, &q.a1, &q.a2};
  V* b[3] = {&q.b0, &q.b1, &q.b2};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (shared[i] >= 0 && shared[k] == shared[i]) *a[i] = *a[k];
    }
    if (shared[i] >= 0) *b[static_cast<std::size_t>(shared[i])] = *a[i];
  }
}

// The same pair seen from b: b's corner j is a's corner inverse[j].
SharedCorners inverse(const SharedCorners& shared) {
  SharedCorners out = kNoSharedCorners;
  for (std::size_t i = 0; i < 3; ++i) {
    if (shared[i] >= 0) out[static_cast<std::size_t>(shared[i])] = static_cast<std::int8_t>(i);
  }
  return out;
}

TriangleTriangleQuery scaled(const TriangleTriangleQuery& q, double s) {
  return {q.a0 * s, q.a1 * s, q.a2 * s, q.b0 * s, q.b1 * s, q.b2 * s};
}

struct Tally {
  int queries = 0;
  int hits = 0;
};

// The entry a DCD uses, with each triangle's plane computed beforehand (once per instant there);
// for a pair without shared corners also the DCD's split of it (the first plane's filter from the
// raw coordinates, then the rest from what it decided), which must give the same answer.
bool with_planes(const TriangleTriangleQuery& q, const SharedCorners& shared) {
  const TrianglePlane plane_a = triangle_plane(q.a0, q.a1, q.a2);
  const TrianglePlane plane_b = triangle_plane(q.b0, q.b1, q.b2);
  const bool answer = triangles_intersect_with_planes(q, shared, plane_a, plane_b);
  if (shared == kNoSharedCorners) {
    FirstSides first{};
    const bool separated =
        first_sides_separate(q.a0.data(), q.a1.data(), q.a2.data(), q.b0.data(), plane_b, first);
    EXPECT_FALSE(separated && answer) << "the first plane's filter separated a meeting pair";
    if (!separated) {
      EXPECT_EQ(triangles_intersect_after_first_sides(q, plane_a, plane_b, first), answer);
    }
  }
  return answer;
}

// The new code, both entries, on q and on its swap, answers `truth`.
void expect_answer(
    const TriangleTriangleQuery& q,
    const SharedCorners& shared,
    bool truth,
    const char* what,
    int n) {
  EXPECT_EQ(triangles_intersect(q, shared), truth) << what << " case " << n;
  EXPECT_EQ(with_planes(q, shared), truth) << what << " case " << n << " (planes given)";
  const TriangleTriangleQuery swapped{q.b0, q.b1, q.b2, q.a0, q.a1, q.a2};
  const SharedCorners inv = inverse(shared);
  EXPECT_EQ(triangles_intersect(swapped, inv), truth) << what << " case " << n << " (swapped)";
  EXPECT_EQ(with_planes(swapped, inv), truth)
      << what << " case " << n << " (swapped, planes given)";
}

// The new code against the brute force; returns the answer.
bool expect_brute(
    const TriangleTriangleQuery& q, const SharedCorners& shared, const char* what, int n) {
  const bool truth = test::brute_intersect(q, shared);
  expect_answer(q, shared, truth, what, n);
  return truth;
}

// Both implementations (and the entry with planes) on q and on its swap; returns the answer. A map
// that names a corner of b twice is judged by the brute force instead: the old code read two
// entries naming one vertex as a shared edge, and answered "no" for a degenerate a reaching into a
// solid b from that vertex; the new code reads them as the one vertex they name, as the brute
// force does (RepeatedSharedCornersAgainstTheBruteForce below).
bool expect_same(
    const TriangleTriangleQuery& q, const SharedCorners& shared, const char* what, int n) {
  if (!injective(shared)) return expect_brute(q, shared, what, n);
  const bool expected = triangles_intersect_reference(q, shared);
  EXPECT_EQ(triangles_intersect(q, shared), expected) << what << " case " << n;
  EXPECT_EQ(with_planes(q, shared), expected) << what << " case " << n << " (planes given)";
  const TriangleTriangleQuery swapped{q.b0, q.b1, q.b2, q.a0, q.a1, q.a2};
  const SharedCorners inv = inverse(shared);
  const bool expected_swapped = triangles_intersect_reference(swapped, inv);
  EXPECT_EQ(triangles_intersect(swapped, inv), expected_swapped)
      << what << " case " << n << " (swapped)";
  EXPECT_EQ(with_planes(swapped, inv), expected_swapped)
      << what << " case " << n << " (swapped, planes given)";
  return expected;
}

// A copy of a query scaled by a power of two (exactly, so the same answer): against the old code,
// or for a map that names a corner twice against the unscaled query's brute-force `answer`
// (rationals of 2^-1000 are slow, the more so in the sanitizer build).
void expect_same_scaled(
    const TriangleTriangleQuery& qs,
    const SharedCorners& shared,
    bool answer,
    const char* what,
    int n) {
  if (injective(shared)) {
    expect_same(qs, shared, what, n);
  } else {
    expect_answer(qs, shared, answer, what, n);
  }
}

// The generators. Grid coordinates are multiples of 1/8 below 4 in magnitude: scaling them by a
// power of two in [2^-1000, 2^300] is exact, so the scaled query has the same answer.
class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}

  double uniform() { return std::uniform_real_distribution<double>(-1.0, 1.0)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  V uniform_point() {
    const double x = uniform(), y = uniform(), z = uniform();
    return {x, y, z};
  }
  V grid_point(int range) {
    const double x = 0.5 * integer(-range, range), y = 0.5 * integer(-range, range),
                 z = 0.5 * integer(-range, range);
    return {x, y, z};
  }
  // A point of the closed triangle (or segment) with dyadic barycentric weights: exact on the grid.
  V on_triangle(const V& p0, const V& p1, const V& p2) {
    const int w0 = integer(0, 4), w1 = integer(0, 4 - w0), w2 = 4 - w0 - w1;
    return (w0 * p0 + w1 * p1 + w2 * p2) / 4.0;
  }
  // x moved by k ulps (k in [-3, 3]) in one coordinate.
  V nudged(V x) {
    const int k = integer(-3, 3);
    double& c = x[integer(0, 2)];
    for (int i = 0; i < std::abs(k); ++i) c = std::nextafter(c, k > 0 ? INFINITY : -INFINITY);
    return x;
  }

  // Grid pairs with contacts by construction (each family a known degeneracy).
  TriangleTriangleQuery grid_query(int family) {
    V a0 = grid_point(2), a1 = grid_point(2), a2 = grid_point(2);
    V b0 = grid_point(2), b1 = grid_point(2), b2 = grid_point(2);
    switch (family) {
      case 0:  // random grid points: coplanar and collinear by chance, often
        break;
      case 1:  // a corner of b on a (inside, on an edge, or at a corner)
        b0 = on_triangle(a0, a1, a2);
        break;
      case 2: {  // an edge of b through a point of a
        const V x = on_triangle(a0, a1, a2);
        const V d = grid_point(1);
        b0 = x + d;
        b1 = x - 0.5 * d;
        break;
      }
      case 3:  // coplanar: every corner in the plane z = const
        a1.z() = a2.z() = b0.z() = b1.z() = b2.z() = a0.z();
        break;
      case 4:  // coplanar in a slanted plane z = x + y
        for (V* p : {&a0, &a1, &a2, &b0, &b1, &b2}) p->z() = p->x() + p->y();
        break;
      case 5:  // a degenerate triangle: a corner on the opposite edge, or two corners equal
        a2 = integer(0, 1) ? a0 : on_triangle(a0, a1, a1);
        break;
      case 6:  // both degenerate
        a2 = on_triangle(a0, a1, a1);
        b2 = integer(0, 1) ? b1 : on_triangle(b0, b1, b1);
        break;
      case 7:  // an edge of b along an edge of a (collinear overlap)
        b0 = on_triangle(a0, a1, a1);
        b1 = on_triangle(a0, a1, a1) + (a1 - a0);
        break;
      default:  // a point triangle
        b1 = b2 = b0 = on_triangle(a0, a1, a2);
        break;
    }
    return {a0, a1, a2, b0, b1, b2};
  }

  std::mt19937_64& rng() { return rng_; }

 private:
  std::mt19937_64 rng_;
};

constexpr int kFamilies = 9;

TEST(TriangleTriangleEquivalence, UniformRandomTriangles) {
  Generator gen(1);
  const auto patterns = all_shared_patterns();
  int hits = 0;
  for (int n = 0; n < 20000; ++n) {
    TriangleTriangleQuery q{
        gen.uniform_point(),
        gen.uniform_point(),
        gen.uniform_point(),
        gen.uniform_point(),
        gen.uniform_point(),
        gen.uniform_point()};
    // Half without shared corners (the common case), half with a random pattern.
    const SharedCorners shared = n % 2 == 0 ? kNoSharedCorners
                                            : patterns[static_cast<std::size_t>(gen.integer(
                                                  0, static_cast<int>(patterns.size()) - 1))];
    apply_shared(q, shared);
    hits += expect_same(q, shared, "uniform", n) ? 1 : 0;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(hits, 2000);
  EXPECT_LT(hits, 18000);
}

// Grid pairs of every family with every shared pattern, each also scaled by powers of two: the
// scaled answer must be the unscaled one (exact arithmetic) and agree with the reference.
TEST(TriangleTriangleEquivalence, GridDegeneraciesEverySharedPatternEveryScale) {
  Generator gen(2);
  const auto patterns = all_shared_patterns();
  ASSERT_EQ(patterns.size(), 64u);
  const double scales[] = {
      0x1p-1000, 0x1p-700, 0x1p-330, 0x1p-100, 0x1p-20, 1.0, 0x1p40, 0x1p150, 0x1p300};
  int n = 0;
  int hits = 0;
  for (int round = 0; round < 5; ++round) {
    for (int family = 0; family < kFamilies; ++family) {
      for (const SharedCorners& shared : patterns) {
        TriangleTriangleQuery q = gen.grid_query(family);
        apply_shared(q, shared);
        const bool answer = expect_same(q, shared, "grid", n);
        hits += answer ? 1 : 0;
        for (const double s : scales) {
          const TriangleTriangleQuery qs = scaled(q, s);
          EXPECT_EQ(triangles_intersect(qs, shared), answer)
              << "grid case " << n << " scaled by " << s;
          expect_same_scaled(qs, shared, answer, "grid (scaled)", n);
        }
        ++n;
        if (::testing::Test::HasFailure()) return;
      }
    }
  }
  EXPECT_GT(hits, n / 8);
  EXPECT_LT(hits, n);
}

// Contacts built exactly, then one corner nudged by up to 3 ulps: the sign filters see values
// within rounding of zero and must hand over to the exact predicates.
TEST(TriangleTriangleEquivalence, NudgedContactsEverySharedPattern) {
  Generator gen(3);
  const auto patterns = all_shared_patterns();
  int n = 0;
  for (int round = 0; round < 8; ++round) {
    for (int family = 0; family < kFamilies; ++family) {
      for (const SharedCorners& shared : patterns) {
        TriangleTriangleQuery q = gen.grid_query(family);
        // Off the grid's dyadic values, so that the differences round.
        const V offset(0.1, 0.3, 0.7);
        for (V* p : {&q.a0, &q.a1, &q.a2, &q.b0, &q.b1, &q.b2}) *p += offset;
        V* corners[6] = {&q.a0, &q.a1, &q.a2, &q.b0, &q.b1, &q.b2};
        V& moved = *corners[gen.integer(0, 5)];
        moved = gen.nudged(moved);
        apply_shared(q, shared);
        const bool answer = expect_same(q, shared, "nudged", n);
        for (const double s : {0x1p-1000, 0x1p-600, 0x1p200, 0x1p300}) {
          expect_same_scaled(scaled(q, s), shared, answer, "nudged (scaled)", n);
        }
        ++n;
        if (::testing::Test::HasFailure()) return;
      }
    }
  }
}

// Nearly coplanar and nearly touching pairs at the scale of a mesh's neighbours: a small triangle
// b on or next to a at a random place, far from the origin, with and without shared corners.
TEST(TriangleTriangleEquivalence, NearlyCoplanarNeighboursFarFromTheOrigin) {
  Generator gen(4);
  const auto patterns = all_shared_patterns();
  int hits = 0;
  for (int n = 0; n < 20000; ++n) {
    const V origin = 1000.0 * gen.uniform_point();
    const double size = std::ldexp(1.0, gen.integer(-20, 0));
    const V a0 = origin + size * gen.uniform_point();
    const V a1 = origin + size * gen.uniform_point();
    const V a2 = origin + size * gen.uniform_point();
    const V e1 = a1 - a0, e2 = a2 - a0;
    // b's corners near a's plane, lifted off it by a relative 0, 1e-16, 1e-12 or 1e-6.
    const double lifts[] = {0.0, 1e-16, 1e-12, 1e-6};
    const V normal = e1.cross(e2);
    V b[3];
    for (V& p : b) {
      const double lift = lifts[gen.integer(0, 3)] * gen.uniform();
      p = a0 + gen.uniform() * e1 + gen.uniform() * e2 + lift * normal / normal.norm() * size;
    }
    TriangleTriangleQuery q{a0, a1, a2, b[0], b[1], b[2]};
    const SharedCorners shared = n % 3 == 0 ? kNoSharedCorners
                                            : patterns[static_cast<std::size_t>(gen.integer(
                                                  0, static_cast<int>(patterns.size()) - 1))];
    apply_shared(q, shared);
    hits += expect_same(q, shared, "near-coplanar", n) ? 1 : 0;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(hits, 1000);
}

// Corners within rounding of the other triangle's plane: b has two corners computed on a's plane
// (inside a, so their true sides, tiny or zero, decide the answer) and one clearly off it, or
// the reverse roles, or a shared corner with the third corner on the plane. The filters see
// determinants of the size of their own error bound here, where a bound taken too small shows.
TEST(TriangleTriangleEquivalence, CornersWithinRoundingOfThePlane) {
  Generator gen(6);
  int hits = 0;
  for (int n = 0; n < 30000; ++n) {
    const V origin = std::ldexp(1.0, gen.integer(-4, 10)) * gen.uniform_point();
    const V a0 = origin + gen.uniform_point(), a1 = origin + gen.uniform_point(),
            a2 = origin + gen.uniform_point();
    const auto on_a = [&] {
      const double u = 0.5 * (1.0 + gen.uniform()), v = 0.5 * (1.0 + gen.uniform()) * (1.0 - u);
      return V(a0 + u * (a1 - a0) + v * (a2 - a0));
    };
    const V off = a0 + gen.uniform_point() + (a1 - a0).cross(a2 - a0) * (n % 2 ? 1.0 : -1.0);
    TriangleTriangleQuery q{a0, a1, a2, on_a(), on_a(), off};
    SharedCorners shared = kNoSharedCorners;
    if (n % 3 == 1) {
      q = {q.b0, q.b1, q.b2, a0, a1, a2};  // the near-plane corners on a's side
    } else if (n % 3 == 2) {
      q.b0 = a0;  // a shared vertex, one free corner of b on a's plane
      shared = {0, -1, -1};
    }
    hits += expect_same(q, shared, "within rounding", n) ? 1 : 0;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(hits, 1000);
  EXPECT_LT(hits, 29000);
}

// Coplanar neighbours across a shared edge whose free corners lie within rounding of the edge's
// line: the triangles are nearly degenerate, their normals small against their permanents, and
// whether the free corners are on the same side (the answer, as they are coplanar) is decided
// by signs the size of the rounding errors.
TEST(TriangleTriangleEquivalence, CoplanarSlivers) {
  Generator gen(7);
  int hits = 0;
  for (int n = 0; n < 20000; ++n) {
    const double z = gen.uniform();  // the plane z = const: coplanar exactly
    const V s0(gen.uniform(), gen.uniform(), z);
    const V s1(gen.uniform(), gen.uniform(), z);
    const auto near_line = [&] {
      V p = s0 + (0.5 + 0.5 * gen.uniform()) * (s1 - s0);
      p.z() = z;
      return gen.integer(0, 1) ? gen.nudged(p) : p;
    };
    V fa = near_line(), fb = near_line();
    fa.z() = fb.z() = z;
    // Every corner order, and the edge shared as (0, 1), (1, 2) or (2, 0) of a.
    const int rot = gen.integer(0, 2);
    V ac[3];
    ac[rot] = s0;
    ac[(rot + 1) % 3] = s1;
    ac[(rot + 2) % 3] = fa;
    const bool flip = gen.integer(0, 1) != 0;
    const TriangleTriangleQuery q{ac[0], ac[1], ac[2], flip ? s1 : s0, flip ? s0 : s1, fb};
    SharedCorners shared = kNoSharedCorners;
    shared[static_cast<std::size_t>(rot)] = static_cast<std::int8_t>(flip ? 1 : 0);
    shared[static_cast<std::size_t>((rot + 1) % 3)] = static_cast<std::int8_t>(flip ? 0 : 1);
    hits += expect_same(q, shared, "coplanar sliver", n) ? 1 : 0;
    if (::testing::Test::HasFailure()) return;
  }
  EXPECT_GT(hits, 1000);
  EXPECT_LT(hits, 19000);
}

// Coordinates at the ends of the double range, mixed within one query: subnormal differences,
// products that underflow, sums near overflow (the filters must stand aside, not guess). Here the
// old code is not always right: the static filter of ccd::orient3d, which it calls, can take a
// sign from a product that underflowed (see Orient3dFilterAllowsForAnUnderflowedProduct below; the
// filter is fixed now). So both are judged by the brute-force rational reference: the new test must
// always be right, and may differ from the old one only where the old one is wrong (which includes
// the repeated shared vertex of RepeatedSharedCornersAgainstTheBruteForce below).
TEST(TriangleTriangleEquivalence, ExtremeMagnitudesMixedInOneQuery) {
  Generator gen(5);
  const auto patterns = all_shared_patterns();
  const int exponents[] = {-1074, -1060, -1022, -700, -540, -400, -100, 0, 100, 300, 500};
  int old_wrong = 0;
  int judged = 0;
  for (int n = 0; n < 1200; ++n) {
    V p[6];
    for (V& v : p) {
      for (int k = 0; k < 3; ++k) {
        const int e = exponents[gen.integer(0, 10)];
        v[k] = gen.integer(0, 3) == 0 ? 0.0 : std::ldexp(gen.uniform(), e);
      }
    }
    TriangleTriangleQuery q{p[0], p[1], p[2], p[3], p[4], p[5]};
    const SharedCorners shared = n % 2 == 0 ? kNoSharedCorners
                                            : patterns[static_cast<std::size_t>(gen.integer(
                                                  0, static_cast<int>(patterns.size()) - 1))];
    apply_shared(q, shared);
    const TriangleTriangleQuery swapped{q.b0, q.b1, q.b2, q.a0, q.a1, q.a2};
    const SharedCorners inv = inverse(shared);
    const bool truth = test::brute_intersect(q, shared);
    ASSERT_EQ(triangles_intersect(q, shared), truth) << "extreme case " << n;
    ASSERT_EQ(triangles_intersect(swapped, inv), truth) << "extreme case " << n << " (swapped)";
    ASSERT_EQ(with_planes(q, shared), truth) << "extreme case " << n << " (planes given)";
    ASSERT_EQ(with_planes(swapped, inv), truth) << "extreme case " << n << " (swapped, planes)";
    old_wrong += triangles_intersect_reference(q, shared) != truth ? 1 : 0;
    old_wrong += triangles_intersect_reference(swapped, inv) != truth ? 1 : 0;
    judged += 2;
  }
  std::cout << "  the old test was wrong on " << old_wrong << " of " << judged
            << " mixed-magnitude queries\n";
}

// The first such query the test above met. ccd::orient3d's static filter (ccd/orientation.hpp)
// used to accept it because its permanent is above 2^64 DBL_MIN, but one product underflows to zero
// and is then multiplied by a coordinate near 2^495: orient3d(a1, b1, b2, b0) came out -1 where
// the exact sign is +1, and the old triangle test answered false. The filter's bound now allows
// for underflowed products: orient3d leaves it to the exact path and is right, and both triangle
// tests answer as the rational reference does. Without the underflow term this fails.
TEST(TriangleTriangleEquivalence, Orient3dFilterAllowsForAnUnderflowedProduct) {
  const TriangleTriangleQuery q{
      V(0x1.12ca1ba4f44ecp-701, -0x1.4f264b29a43d4p-1, 0x0p+0),
      V(-0x1.09af6c1df1ea4p-703, -0x0.d241fed99bdc4p-1022, 0x1.b5b6f0ba74bd4p-542),
      V(0x0.084c35a14ed44p-1022, -0x1.3a885c59a8e1ap-542, 0x1.0c1744f801524p+498),
      V(0x0p+0, -0x1.09ec8af114f4p-701, -0x1.a68b1efb77874p-1),
      V(-0x1.e745f9aba8506p-541, 0x0.0000000000001p-1022, 0x1.220f3fe73f34p+495),
      V(-0x1.50467259ed7c6p-401, -0x1.c330bd81b2c5ap-401, 0x0p+0)};
  EXPECT_TRUE(test::brute_intersect(q, kNoSharedCorners));
  EXPECT_EQ(orient3d_exact(q.a1, q.b1, q.b2, q.b0), 1);
  EXPECT_EQ(orient3d(q.a1, q.b1, q.b2, q.b0), 1);
  EXPECT_TRUE(triangles_intersect(q));
  EXPECT_TRUE(triangles_intersect_reference(q));
}

// A zero-area triangle a that repeats the vertex it shares with a solid neighbour b (a0 and a1
// are both b's corner 1) and reaches into b from it: they meet along [o, a2], beyond the vertex.
// The old code counted the two entries as a shared edge and answered no.
TEST(TriangleTriangleEquivalence, RepeatedSharedVertexReachingIntoASolidNeighbour) {
  const V o(0, 0, 0);
  const TriangleTriangleQuery q{o, o, V(0.25, 0.25, 0), V(1, 0, 0), o, V(0, 1, 0)};
  const SharedCorners shared{1, 1, -1};
  EXPECT_TRUE(test::brute_intersect(q, shared));
  EXPECT_FALSE(triangles_intersect_reference(q, shared));  // the old answer
  EXPECT_TRUE(triangles_intersect(q, shared));
  EXPECT_TRUE(with_planes(q, shared));
  const TriangleTriangleQuery swapped{q.b0, q.b1, q.b2, q.a0, q.a1, q.a2};
  EXPECT_TRUE(triangles_intersect(swapped, inverse(shared)));
  // The same vertex named once, by either corner of a: the same answer.
  EXPECT_TRUE(triangles_intersect(q, {1, -1, -1}));
  EXPECT_TRUE(triangles_intersect(q, {-1, 1, -1}));
  // Pointing away from b, or out of its plane, a meets b at the vertex alone.
  for (const V& a2 : {V(-0.25, -0.25, 0), V(0.25, 0.25, 0.5)}) {
    const TriangleTriangleQuery away{o, o, a2, q.b0, q.b1, q.b2};
    EXPECT_FALSE(test::brute_intersect(away, shared));
    EXPECT_FALSE(triangles_intersect(away, shared));
  }
  // Its far corner b's corner 0 too ({1, 1, 0}): a is b's edge (1, 0), the shared part.
  const TriangleTriangleQuery edge{o, o, q.b0, q.b0, q.b1, q.b2};
  EXPECT_FALSE(test::brute_intersect(edge, {1, 1, 0}));
  EXPECT_FALSE(triangles_intersect(edge, {1, 1, 0}));
}

// A pair around the vertex v = b's corner that `shared` names twice or three times. b's shape:
// solid, solid in a plane z = const, a corner on the segment of the others, two corners equal, a
// point. a's free corner (if it has one): a grid point, in b's angle at v, along an edge of b from
// v (short of, at and beyond its end), opposite b's angle, at v, or just off b's plane. a's shared
// corners take b's positions. With `nudged`, everything moves off the dyadic grid (so that
// differences round) and one corner moves by a few ulps: near-degenerate instead of exact.
TriangleTriangleQuery repeated_vertex_query(
    Generator& gen, const SharedCorners& shared, int b_shape, int c_shape, bool nudged) {
  int j = -1;  // the corner of b named more than once
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t k = 0; k < i; ++k) {
      if (shared[i] >= 0 && shared[i] == shared[k]) j = shared[i];
    }
  }
  assert(j >= 0);
  const auto ju = static_cast<std::size_t>(j);
  V b[3] = {gen.grid_point(2), gen.grid_point(2), gen.grid_point(2)};
  const std::size_t m = (ju + 1 + static_cast<std::size_t>(gen.integer(0, 1))) % 3;  // not v
  const std::size_t other = 3 - ju - m;
  switch (b_shape) {
    case 0:
      break;
    case 1:
      b[1].z() = b[2].z() = b[0].z();
      break;
    case 2:
      b[m] = gen.on_triangle(b[ju], b[other], b[other]);
      break;
    case 3:
      b[m] = gen.integer(0, 1) ? b[ju] : b[other];
      break;
    default:
      b[0] = b[1] = b[2];
      break;
  }
  const V& v = b[ju];
  const V p = gen.on_triangle(b[0], b[1], b[2]);
  const double t = 0.5 * gen.integer(1, 4);  // 1/2 .. 2
  V c;
  switch (c_shape) {
    case 0:
      c = gen.grid_point(2);
      break;
    case 1:
      c = v + t * (p - v);
      break;
    case 2:
      c = v + t * (b[m] - v);
      break;
    case 3:
      c = v - t * (p - v);
      break;
    case 4:
      c = v;
      break;
    default:
      c = v + t * (p - v) + 0.125 * (b[m] - v).cross(b[other] - v);
      break;
  }
  if (nudged) {
    const V offset(0.1, 0.3, 0.7);
    for (V& x : b) x += offset;
    c += offset;
    V* corners[4] = {&b[0], &b[1], &b[2], &c};
    V& moved = *corners[gen.integer(0, 3)];
    moved = gen.nudged(moved);
  }
  V a[3];
  for (std::size_t i = 0; i < 3; ++i)
    a[i] = shared[i] >= 0 ? b[static_cast<std::size_t>(shared[i])] : c;
  return {a[0], a[1], a[2], b[0], b[1], b[2]};
}

// Every map that names a corner of b twice or three times (30 of the 64) on the pairs above, exact
// and nudged, the exact ones also scaled by powers of two: the new code, both entries and both
// orders (seen from b, the repeated vertex is named once and a is the triangle with a repeated
// point), against the brute force. The sweep must meet the case the old code got wrong.
TEST(TriangleTriangleEquivalence, RepeatedSharedCornersAgainstTheBruteForce) {
  Generator gen(8);
  std::vector<SharedCorners> repeated;
  for (const SharedCorners& s : all_shared_patterns()) {
    if (!injective(s)) repeated.push_back(s);
  }
  ASSERT_EQ(repeated.size(), 30u);
  const double scales[] = {0x1p-1000, 0x1p-330, 0x1p-20, 0x1p40, 0x1p300};
  int n = 0;
  int hits = 0;
  int old_wrong = 0;
  for (int round = 0; round < 4; ++round) {
    const bool nudged = round % 2 == 1;
    for (int b_shape = 0; b_shape < 5; ++b_shape) {
      for (int c_shape = 0; c_shape < 6; ++c_shape) {
        for (const SharedCorners& shared : repeated) {
          const TriangleTriangleQuery q =
              repeated_vertex_query(gen, shared, b_shape, c_shape, nudged);
          const bool truth = expect_brute(q, shared, "repeated", n);
          hits += truth ? 1 : 0;
          old_wrong += triangles_intersect_reference(q, shared) != truth ? 1 : 0;
          if (!nudged) {
            for (const double s : scales) {
              expect_answer(scaled(q, s), shared, truth, "repeated (scaled)", n);
            }
          }
          ++n;
          if (::testing::Test::HasFailure()) return;
        }
      }
    }
  }
  EXPECT_GT(hits, n / 20);
  EXPECT_LT(hits, n / 2);
  EXPECT_GT(old_wrong, 0);
  std::cout << "  " << hits << " of " << n << " repeated-vertex queries intersect; the old test was"
            << " wrong on " << old_wrong << "\n";
}

}  // namespace
}  // namespace skelcd::ccd
