// triangles_intersect against an independent brute-force rational reference
// (tests/ccd/triangle_triangle_brute.hpp).

#include <gmpxx.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "ccd/orientation.hpp"
#include "ccd/triangle_triangle.hpp"
#include "tests/ccd/triangle_triangle_brute.hpp"

namespace skelcd::ccd {
namespace {

using V = Eigen::Vector3d;
using test::brute_intersect;
using Q3 = std::array<mpq_class, 3>;

Q3 rational(const V& p) { return {mpq_class(p.x()), mpq_class(p.y()), mpq_class(p.z())}; }

TriangleTriangleQuery tri(V a0, V a1, V a2, V b0, V b1, V b2) { return {a0, a1, a2, b0, b1, b2}; }

TEST(TriangleTriangle, HandPickedCases) {
  const V o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
  // Piercing, touching at a point, apart, coplanar overlapping, coplanar apart, coplanar touching edges.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(0.2, 0.2, -1), V(0.2, 0.2, 1), V(2, 2, 0))));
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(0.2, 0.2, 0), V(0.2, 0.3, 1), V(0.3, 0.2, 1))));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, V(0.2, 0.2, 1e-12), V(0.2, 0.3, 1), V(0.3, 0.2, 1))));
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(0.2, 0.2, 0), V(2, 0.2, 0), V(0.2, 2, 0))));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, V(2, 2, 0), V(3, 2, 0), V(2, 3, 0))));
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(1, 0, 0), V(2, 0, 0), V(1, 1, 0))));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, V(1 + 1e-15, 0, 0), V(2, 0, 0), V(1, 1, 0))));
  // Degenerate: a segment triangle through the face; a point triangle on an edge.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(0.3, 0.3, -1), V(0.3, 0.3, 1), V(0.3, 0.3, 0.5))));
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, V(0.5, 0, 0), V(0.5, 0, 0), V(0.5, 0, 0))));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, V(0.5, -1e-300, 0), V(0.5, -1e-300, 0), V(0.5, -1e-300, 0))));
}

TEST(TriangleTriangle, SharedVertexAndEdge) {
  const V o(0, 0, 0), x(1, 0, 0), y(0, 1, 0);
  // A fan around o: neighbours share o and meet nowhere else.
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, o, V(-1, 0, 0), V(0, -1, 0.5)), {0, -1, -1}));
  // Shared vertex, and the other triangle folds back through this one.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, o, V(0.5, 0.5, 1), V(0.5, 0.5, -1)), {0, -1, -1}));
  // Shared vertex, coplanar, overlapping wedge.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, o, V(1, 1, 0), V(2, 0.5, 0)), {0, -1, -1}));
  // Shared vertex, coplanar, only the vertex in common.
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, o, V(-1, 0, 0), V(-1, -1, 0)), {0, -1, -1}));
  // Without the shared flag the common vertex counts.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, o, V(-1, 0, 0), V(-1, -1, 0))));
  // Shared edge o-x: bent (not coplanar), flat on the other side, folded onto the same side.
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, x, o, V(0.5, -1, 1)), {1, 0, -1}));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, x, o, V(0.5, -1, 0)), {1, 0, -1}));
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, x, o, V(0.5, 0.25, 0)), {1, 0, -1}));
  // The same triangle.
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, y, o, x), {1, 2, 0}));
  // A degenerate neighbour: shared vertex o, the other two corners collinear with o along x.
  EXPECT_TRUE(triangles_intersect(tri(o, x, y, o, V(0.5, 0, 0), V(2, 0, 0)), {0, -1, -1}));
  EXPECT_FALSE(triangles_intersect(tri(o, x, y, o, V(-0.5, 0, 0), V(-2, 0, 0)), {0, -1, -1}));
}

// Random triangles on a small grid (exact degeneracies everywhere), sometimes sharing corners.
TEST(TriangleTriangle, AgreesWithBruteForceOnGridTriangles) {
  std::mt19937_64 rng(42);
  std::uniform_int_distribution<int> coord(-1, 2);
  const auto grid_point = [&] {
    const double x = 0.5 * coord(rng);
    const double y = 0.5 * coord(rng);
    const double z = 0.5 * coord(rng);
    return V(x, y, z);
  };
  int hits = 0;
  int shared_cases = 0;
  for (int n = 0; n < 1500; ++n) {
    TriangleTriangleQuery q{grid_point(), grid_point(), grid_point(), grid_point(), grid_point(), grid_point()};
    SharedCorners shared = kNoSharedCorners;
    const int share = std::uniform_int_distribution<int>(0, 3)(rng);  // 0: none, 1: vertex, 2: edge
    if (share == 1 || share == 2) {
      V* a[3] = {&q.a0, &q.a1, &q.a2};
      V* b[3] = {&q.b0, &q.b1, &q.b2};
      int perm[3] = {0, 1, 2};
      std::shuffle(perm, perm + 3, rng);
      for (int s = 0; s < share; ++s) {
        const int i = s;
        const int j = perm[s];
        *b[j] = *a[i];
        shared[static_cast<std::size_t>(i)] = static_cast<std::int8_t>(j);
      }
      ++shared_cases;
    }
    const bool expected = brute_intersect(q, shared);
    ASSERT_EQ(triangles_intersect(q, shared), expected) << "case " << n;
    hits += expected ? 1 : 0;
  }
  EXPECT_GT(hits, 200);
  EXPECT_LT(hits, 1300);
  EXPECT_GT(shared_cases, 500);
}

// Nearly degenerate doubles: contacts built exactly on a grid, then nudged by one ulp, so that the
// floating-point filter cannot decide and the exact fallback must.
TEST(TriangleTriangle, AgreesWithBruteForceNextToDegeneracies) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> coord(-2, 2);
  std::uniform_int_distribution<int> pick(0, 17);
  int hits = 0;
  for (int n = 0; n < 600; ++n) {
    std::array<V, 6> p;
    for (auto& v : p) {
      const double x = 0.25 * coord(rng) + 0.1;
      const double y = 0.25 * coord(rng) + 0.3;
      const double z = 0.25 * coord(rng) + 0.7;
      v = V(x, y, z);
    }
    const int k = pick(rng);
    double& c = p[static_cast<std::size_t>(k / 3)][k % 3];
    c = std::nextafter(c, (n % 2) ? 10.0 : -10.0);
    const TriangleTriangleQuery q{p[0], p[1], p[2], p[3], p[4], p[5]};
    const bool expected = brute_intersect(q, kNoSharedCorners);
    ASSERT_EQ(triangles_intersect(q), expected) << "case " << n;
    hits += expected ? 1 : 0;
  }
  EXPECT_GT(hits, 50);
}

TEST(Orientation, ExactOnNearlyCoplanarPoints) {
  const V a(0.1, 0.2, 0.3), b(1e8 + 0.1, 0.2, 0.3), c(0.1, 1e8 + 0.2, 0.3);
  EXPECT_EQ(orient3d(a, b, c, V(5, 7, 0.3)), 0);
  EXPECT_EQ(orient3d(a, b, c, V(5, 7, std::nextafter(0.3, 1.0))), 1);
  EXPECT_EQ(orient3d(a, b, c, V(5, 7, std::nextafter(0.3, 0.0))), -1);
  // Scaled to the underflow range: the filter hands over to the exact path.
  const double s = 1e-300;
  EXPECT_EQ(orient3d(a * s, b * s, c * s, V(5, 7, 0.4) * s), 1);
}

// The exact sign of (d − a) · ((b − a) × (c − a)), in rationals (the reference for the filters).
int rational_orient3d(const V& a, const V& b, const V& c, const V& d) {
  const Q3 qa = rational(a), qb = rational(b), qc = rational(c), qd = rational(d);
  Q3 u, v, w;
  for (std::size_t k = 0; k < 3; ++k) {
    u[k] = qb[k] - qa[k];
    v[k] = qc[k] - qa[k];
    w[k] = qd[k] - qa[k];
  }
  const mpq_class det = w[0] * (u[1] * v[2] - u[2] * v[1]) + w[1] * (u[2] * v[0] - u[0] * v[2]) +
                        w[2] * (u[0] * v[1] - u[1] * v[0]);
  return (det > 0) - (det < 0);
}

// The static filters in front of orient3d and of the degeneracy test: never a wrong sign (a sign
// only where the exact value has it, undecided on exact zeros), on generic points, exactly
// coplanar grid points, the same nudged by one ulp, rotated flat patches (coplanar up to
// rounding) and scales down to the underflow range and up to 1e150.
TEST(Orientation, StaticFiltersNeverContradictTheExactSign) {
  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> small(-3, 3);
  std::uniform_int_distribution<int> corner(0, 11);
  const double scales[] = {1.0, 1e-3, 1e8, 1e-150, 1e150, 1e-160};
  int decided = 0;
  int generic = 0;
  int zeros = 0;
  for (int n = 0; n < 12000; ++n) {
    std::array<V, 4> p;
    const int kind = n % 4;
    for (auto& q : p) {
      if (kind == 0) {
        q = V(unit(rng), unit(rng), unit(rng));
      } else {
        // On the plane z = x + 2y (exactly coplanar with small integers).
        const double x = small(rng), y = small(rng);
        q = V(x, y, x + 2 * y);
      }
    }
    if (kind == 2) {
      const int k = corner(rng);
      double& c = p[static_cast<std::size_t>(k / 3)][k % 3];
      c = std::nextafter(c, (n % 8 < 4) ? 10.0 : -10.0);
    }
    if (kind == 3) {
      // A rotation in double: coplanar only up to rounding.
      const Eigen::Matrix3d r =
          Eigen::AngleAxisd(unit(rng) * 3.0, V(unit(rng), unit(rng), 1.0).normalized())
              .toRotationMatrix();
      for (auto& q : p) q = r * q;
    }
    const double s = scales[static_cast<std::size_t>(n / 4) % std::size(scales)];
    for (auto& q : p) q *= s;
    const int exact = rational_orient3d(p[0], p[1], p[2], p[3]);
    const int fast = detail::orient3d_static(p[0], p[1], p[2], p[3]);
    ASSERT_TRUE(fast == detail::kUndecided || fast == exact) << "case " << n;
    ASSERT_EQ(orient3d(p[0], p[1], p[2], p[3]), exact) << "case " << n;
    zeros += exact == 0 ? 1 : 0;
    if (kind == 0 && s >= 1e-3 && s <= 1e8) {
      ++generic;
      decided += fast != detail::kUndecided ? 1 : 0;
    }
    for (int axis = 0; axis < 3; ++axis) {
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      const Q3 qa = rational(p[0]), qb = rational(p[1]), qc = rational(p[2]);
      const auto ui = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
      const mpq_class value =
          (qb[ui] - qa[ui]) * (qc[uj] - qa[uj]) - (qb[uj] - qa[uj]) * (qc[ui] - qa[ui]);
      const int component = (value > 0) - (value < 0);
      const int f = detail::cross_component_static(p[0], p[1], p[2], i, j);
      ASSERT_TRUE(f == detail::kUndecided || f == component) << "case " << n << " axis " << axis;
    }
  }
  EXPECT_GT(zeros, 2000) << "the exactly coplanar cases must be there";
  // The filter is what makes orient3d cheap: it decides generic points.
  EXPECT_GT(decided, generic * 99 / 100);
}

// Neighbours across an edge of a rotated, nearly flat or folded strip (the case the side-first
// order of the shared-edge test is for) agree with the brute-force reference.
TEST(TriangleTriangle, SharedEdgeNeighboursOfRotatedStrips) {
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int hits = 0;
  for (int n = 0; n < 400; ++n) {
    // Shared edge s0–s1, free corners fa and fb: flat (fb across the edge), folded onto fa's side
    // (same side, in the plane), or bent by a small angle.
    const V s0(0, 0, 0), s1(1, 0, 0);
    const V fa(unit(rng), 1.0, 0.0);
    const int kind = n % 3;
    V fb(unit(rng), kind == 1 ? 0.5 : -1.0, 0.0);
    if (kind == 2) fb.z() = 1e-9 * unit(rng);
    // Every sixth case unrotated: exactly flat or exactly folded (then they overlap).
    const Eigen::Matrix3d r =
        n % 6 == 1 ? Eigen::Matrix3d::Identity()
                   : Eigen::AngleAxisd(unit(rng) * 3.0, V(unit(rng), unit(rng), 1.0).normalized())
                         .toRotationMatrix();
    const TriangleTriangleQuery q{r * s0, r * s1, r * fa, r * s1, r * s0, r * fb};
    const SharedCorners shared{1, 0, -1};
    const bool expected = brute_intersect(q, shared);
    ASSERT_EQ(triangles_intersect(q, shared), expected) << "case " << n;
    hits += expected ? 1 : 0;
  }
  EXPECT_GT(hits, 0);
}

// A zero-area triangle (three collinear corners) next to a non-degenerate one, sharing a corner or
// two: the case real rigs have at collapsed seams, decided without rationals (flat against solid).
// On a grid, so that the flat triangle often lies exactly in the solid one's plane, with its line
// pointing into the solid one's corner, along an edge, away from it, or out of the plane.
TEST(TriangleTriangle, FlatNeighboursOfSolidTrianglesAgreeWithBruteForce) {
  std::mt19937_64 rng(2026);
  std::uniform_int_distribution<int> coord(-2, 2);
  const auto grid = [&](bool in_plane) {
    return V(0.5 * coord(rng), 0.5 * coord(rng), in_plane ? 0.0 : 0.5 * coord(rng));
  };
  int hits = 0, misses = 0, coplanar = 0, two_shared = 0;
  for (int n = 0; n < 4000; ++n) {
    const bool planar = n % 4 != 3;  // mostly in the plane z = 0, where the exact zeros are
    V s[3] = {grid(true), grid(true), grid(true)};
    if (!planar) s[2] = grid(false);
    if (orient3d(s[0], s[1], s[2], s[0] + V(0, 0, 1)) == 0 &&
        orient3d(s[0], s[1], s[2], s[0] + V(1, 0, 0)) == 0 &&
        orient3d(s[0], s[1], s[2], s[0] + V(0, 1, 0)) == 0) {
      continue;  // the solid triangle came out degenerate
    }
    const int share = 1 + (n % 3 == 0 ? 1 : 0);
    const int v = std::uniform_int_distribution<int>(0, 2)(rng);
    V f[3];
    f[0] = s[v];
    SharedCorners shared = kNoSharedCorners;  // flat corner -> solid corner
    shared[0] = static_cast<std::int8_t>(v);
    if (share == 2) {
      const int w = (v + 1 + (n / 3) % 2) % 3;
      f[1] = s[w];
      shared[1] = static_cast<std::int8_t>(w);
      f[2] = f[0] + 0.5 * coord(rng) * (f[1] - f[0]);
      ++two_shared;
    } else {
      V d = grid(n % 8 != 7);
      if (n % 5 == 0) d = s[(v + 1) % 3] - s[v];  // along an edge of the solid triangle
      f[1] = f[0] + 0.5 * coord(rng) * d;
      f[2] = f[0] + 0.5 * coord(rng) * d;
    }
    const int at =
        std::uniform_int_distribution<int>(0, 2)(rng);  // where the flat one's shared corners go
    std::swap(f[0], f[at]);
    std::swap(shared[0], shared[static_cast<std::size_t>(at)]);
    const bool flat_first = n % 2 == 0;
    TriangleTriangleQuery q = flat_first
                                  ? TriangleTriangleQuery{f[0], f[1], f[2], s[0], s[1], s[2]}
                                  : TriangleTriangleQuery{s[0], s[1], s[2], f[0], f[1], f[2]};
    SharedCorners arg = shared;
    if (!flat_first) {
      arg = kNoSharedCorners;
      for (int i = 0; i < 3; ++i) {
        if (shared[static_cast<std::size_t>(i)] >= 0)
          arg[static_cast<std::size_t>(shared[static_cast<std::size_t>(i)])] =
              static_cast<std::int8_t>(i);
      }
    }
    coplanar += (orient3d(s[0], s[1], s[2], f[0]) == 0 && orient3d(s[0], s[1], s[2], f[1]) == 0 &&
                 orient3d(s[0], s[1], s[2], f[2]) == 0)
                    ? 1
                    : 0;
    const bool expected = brute_intersect(q, arg);
    ASSERT_EQ(triangles_intersect(q, arg), expected) << "case " << n;
    (expected ? hits : misses) += 1;
  }
  // Both answers, many exactly coplanar cases, and shared edges among them.
  EXPECT_GT(hits, 300);
  EXPECT_GT(misses, 300);
  EXPECT_GT(coplanar, 1500);
  EXPECT_GT(two_shared, 800);
}

}  // namespace
}  // namespace skelcd::ccd
