// Continuous orientation classes against exact evaluation: an H⁺ (H⁻) triangle must have f > 0
// (f < 0) at every densely sampled instant, with f evaluated in exact rational arithmetic; line
// observers likewise at every corner and at interior points, each viewed from its exact nearest
// point of the segment. Plus hand-made cases with known classes.
#include <gmpxx.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <random>

#include "ccd/coplanarity_screen.hpp"
#include "ccd/detail/conservative_pipeline.hpp"
#include "ccd/detail/screen_x4.hpp"
#include "ccd/detail/trilinear_cubic.hpp"
#include "clustering/orientation_class.hpp"

namespace skelcd::clustering {
namespace {

using V3 = Eigen::Vector3d;
using Q3 = std::array<mpq_class, 3>;

Q3 exact(const V3& v) { return {mpq_class(v.x()), mpq_class(v.y()), mpq_class(v.z())}; }
Q3 lerp(const Q3& a, const Q3& b, const mpq_class& t) {
  return {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
}
Q3 sub(const Q3& a, const Q3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
mpq_class dot(const Q3& a, const Q3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Q3 cross(const Q3& a, const Q3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

struct ExactTriangle {
  Q3 a0, b0, c0, a1, b1, c1;
  explicit ExactTriangle(const MovingTriangle& t)
      : a0(exact(t.a_t0)), b0(exact(t.b_t0)), c0(exact(t.c_t0)),
        a1(exact(t.a_t1)), b1(exact(t.b_t1)), c1(exact(t.c_t1)) {}
  std::array<Q3, 3> at(const mpq_class& t) const {
    return {lerp(a0, a1, t), lerp(b0, b1, t), lerp(c0, c1, t)};
  }
};

/// Exact sign of f(t) = (a(t) − q(t)) · n(t).
int exact_point_sign(const MovingTriangle& tri, const MovingPoint& q, const mpq_class& t) {
  const auto p = ExactTriangle(tri).at(t);
  const Q3 qt = lerp(exact(q.t0), exact(q.t1), t);
  const Q3 n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
  return sgn(dot(sub(p[0], qt), n));
}

/// Exact sign of h(x, t) = (x − c(x)) · n(t), c(x) the nearest point of the segment at t, for x
/// the point with barycentric coordinates (u, v, w) of the triangle.
int exact_line_sign(const MovingTriangle& tri, const MovingSegment& s, const mpq_class& t,
                    const std::array<mpq_class, 3>& bary) {
  const auto p = ExactTriangle(tri).at(t);
  Q3 x;
  for (std::size_t k = 0; k < 3; ++k) x[k] = bary[0] * p[0][k] + bary[1] * p[1][k] + bary[2] * p[2][k];
  const Q3 q1 = lerp(exact(s.q1_t0), exact(s.q1_t1), t);
  const Q3 q2 = lerp(exact(s.q2_t0), exact(s.q2_t1), t);
  const Q3 d = sub(q2, q1);
  const mpq_class dd = dot(d, d);
  mpq_class sigma = 0;
  if (dd > 0) {
    sigma = dot(sub(x, q1), d) / dd;
    if (sigma < 0) sigma = 0;
    if (sigma > 1) sigma = 1;
  }
  const Q3 c = lerp(q1, q2, sigma);
  const Q3 n = cross(sub(p[1], p[0]), sub(p[2], p[0]));
  return sgn(dot(sub(x, c), n));
}

constexpr int kSamples = 64;  // t = k / 64, k = 0 … 64

V3 random_point(std::mt19937_64& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

MovingTriangle random_triangle(std::mt19937_64& rng) {
  // A small triangle near the origin, moving by up to its own size.
  const V3 centre = random_point(rng, 1.0);
  MovingTriangle t;
  t.a_t0 = centre + random_point(rng, 0.3);
  t.b_t0 = centre + random_point(rng, 0.3);
  t.c_t0 = centre + random_point(rng, 0.3);
  t.a_t1 = t.a_t0 + random_point(rng, 0.3);
  t.b_t1 = t.b_t0 + random_point(rng, 0.3);
  t.c_t1 = t.c_t0 + random_point(rng, 0.3);
  return t;
}

// --- hand-made -------------------------------------------------------------------------------

MovingTriangle still(const V3& a, const V3& b, const V3& c) { return {a, b, c, a, b, c}; }

TEST(OrientationClass, PointObserverKnownCases) {
  // Counter-clockwise seen from +z: the normal points up.
  const auto tri = still({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  EXPECT_EQ(classify(tri, MovingPoint{{0.2, 0.2, -1}, {0.2, 0.2, -1}}), OrientationClass::positive);
  EXPECT_EQ(classify(tri, MovingPoint{{0.2, 0.2, 1}, {0.2, 0.2, 1}}), OrientationClass::negative);
  // The observer passes through the triangle's plane within the interval.
  EXPECT_EQ(classify(tri, MovingPoint{{5, 5, -1}, {5, 5, 1}}), OrientationClass::uncertain);
  // The observer in the plane for the whole interval: f ≡ 0.
  EXPECT_EQ(classify(tri, MovingPoint{{3, 3, 0}, {4, 4, 0}}), OrientationClass::uncertain);
  // A triangle that flips over (c goes through the plane of a, b and the observer).
  MovingTriangle flip = tri;
  flip.c_t1 = {0, -1, 0};
  EXPECT_EQ(classify(flip, MovingPoint{{0.2, 0.2, -1}, {0.2, 0.2, -1}}),
            OrientationClass::uncertain);
  // Degenerate (zero-area) triangle: never proven.
  EXPECT_EQ(classify(still({0, 0, 0}, {1, 0, 0}, {2, 0, 0}), MovingPoint{{0, 0, -1}, {0, 0, -1}}),
            OrientationClass::uncertain);
  // Observer and triangle translating together keep their class.
  MovingTriangle moving = tri;
  const V3 shift(10, -3, 7);
  moving.a_t1 += shift;
  moving.b_t1 += shift;
  moving.c_t1 += shift;
  EXPECT_EQ(classify(moving, MovingPoint{{0.2, 0.2, -1}, V3(0.2, 0.2, -1) + shift}),
            OrientationClass::positive);
}

TEST(OrientationClass, LineObserverUsesTheNearestPoints) {
  // A small triangle in the plane x + z = −0.85 (normal (1, 0, 1)) above the left end of a segment
  // along x at z = −0.1. Endpoint q1 = (−1, 0, −0.1) is behind it, q2 = (1, 0, −0.1) in front; the
  // triangle's nearest points on the segment are near x = −0.85: behind it. Positive.
  const auto tri = still({-0.85, 0.0, 0.0}, {-0.8, 0.05, -0.05}, {-0.9, 0.05, 0.05});
  const MovingSegment seg{{-1, 0, -0.1}, {1, 0, -0.1}, {-1, 0, -0.1}, {1, 0, -0.1}};
  const V3 n = (tri.b_t0 - tri.a_t0).cross(tri.c_t0 - tri.a_t0);
  ASSERT_GT(n.x(), 0.0);
  ASSERT_GT(n.z(), 0.0);
  EXPECT_EQ(classify(tri, MovingPoint{seg.q1_t0, seg.q1_t1}), OrientationClass::positive);
  EXPECT_EQ(classify(tri, MovingPoint{seg.q2_t0, seg.q2_t1}), OrientationClass::negative);
  EXPECT_EQ(classify(tri, seg), OrientationClass::positive);
  const ProjectionRange r = projection_range(tri, seg);
  EXPECT_LE(r.lo, 0.05);
  EXPECT_GE(r.hi, 0.1);
  EXPECT_LT(r.hi, 0.11);
  // A segment through the triangle's plane near the triangle: uncertain.
  const MovingSegment through{{-0.85, 0, -1}, {-0.85, 0, 1}, {-0.85, 0, -1}, {-0.85, 0, 1}};
  EXPECT_EQ(classify(tri, through), OrientationClass::uncertain);
  // A segment that shrinks to a point within the interval: σ unknown, [0, 1] is used.
  const MovingSegment collapsing{{-1, 0, -0.1}, {1, 0, -0.1}, {1, 0, -0.1}, {-1, 0, -0.1}};
  const ProjectionRange all = projection_range(tri, collapsing);
  EXPECT_EQ(all.lo, 0.0);
  EXPECT_EQ(all.hi, 1.0);
}

// --- against exact evaluation ------------------------------------------------------------------

TEST(OrientationClass, PointClassesHoldAtEveryExactSample) {
  std::mt19937_64 rng(2024);
  int proven = 0;
  int positives = 0;
  int negatives = 0;
  for (int trial = 0; trial < 800; ++trial) {
    const MovingTriangle tri = random_triangle(rng);
    // Observers from far away to almost in the plane, some moving through it.
    const double reach = trial % 3 == 0 ? 0.5 : 3.0;
    const MovingPoint q{random_point(rng, reach), random_point(rng, reach)};
    const OrientationClass c = classify(tri, q);
    if (c == OrientationClass::uncertain) continue;
    ++proven;
    (c == OrientationClass::positive ? positives : negatives)++;
    const int expected = c == OrientationClass::positive ? 1 : -1;
    for (int k = 0; k <= kSamples; ++k) {
      ASSERT_EQ(exact_point_sign(tri, q, mpq_class(k, kSamples)), expected)
          << "trial " << trial << " t = " << k << "/" << kSamples << " class " << to_string(c);
    }
  }
  // The test must exercise both proven classes a good number of times.
  EXPECT_GT(positives, 100);
  EXPECT_GT(negatives, 100);
  EXPECT_LT(proven, 800);  // and some uncertain ones
}

// screen_classes_x4 (a point observer's four triangles screened in one vector): a lane is settled
// exactly when classify's own screen (the cubic of a − q, b − a, c − a) is certain, and then its
// class is classify's; the AVX2 and baseline builds of the screen agree bit for bit. On random
// triangles seen from near and far, and from observers passing close to their planes.
TEST(OrientationClass, FourPointClassesAtOnceAreClassifysBitForBit) {
  std::mt19937_64 rng(4242);
  int settled = 0, unsettled = 0, positives = 0, negatives = 0;
  for (int batch = 0; batch < 1500; ++batch) {
    std::array<MovingTriangle, 4> tris;
    for (auto& t : tris) t = random_triangle(rng);
    MovingPoint q{random_point(rng, batch % 3 == 0 ? 0.5 : 3.0), V3::Zero()};
    q.t1 = q.t0 + random_point(rng, 0.3);
    if (batch % 5 == 0) {
      // Close to the first triangle's plane at the start.
      const MovingTriangle& t = tris[0];
      const V3 n = (t.b_t0 - t.a_t0).cross(t.c_t0 - t.a_t0).normalized();
      q.t0 = t.a_t0 + 0.3 * (t.b_t0 - t.a_t0) + 1e-9 * n;
    }
    ccd::FaceCorners c0{}, c1{};
    for (std::size_t k = 0; k < 4; ++k) {
      c0[k] = {tris[k].a_t0.data(), tris[k].b_t0.data(), tris[k].c_t0.data()};
      c1[k] = {tris[k].a_t1.data(), tris[k].b_t1.data(), tris[k].c_t1.data()};
    }
    const ccd::CoplanarityScreens fast =
        ccd::point_faces_screen_x4(q.t0.data(), q.t1.data(), c0, c1);
    const ccd::CoplanarityScreens base =
        ccd::detail::point_faces_screen_x4_baseline(q.t0.data(), q.t1.data(), c0, c1);
    ASSERT_EQ(fast.apart, base.apart) << batch;
    for (std::size_t k = 0; k < 4; ++k) {
      for (std::size_t i = 0; i < 4; ++i) {
        ASSERT_EQ(
            std::bit_cast<std::uint64_t>(fast.coefficients[k][i]),
            std::bit_cast<std::uint64_t>(base.coefficients[k][i]))
            << batch;
      }
    }
    const ScreenedClasses got = screen_classes_x4(c0, c1, q);
    for (std::size_t k = 0; k < 4; ++k) {
      const MovingTriangle& t = tris[k];
      const ccd::detail::TrilinearScreen own = ccd::detail::trilinear_screen(
          {t.a_t0 - q.t0, t.b_t0 - t.a_t0, t.c_t0 - t.a_t0},
          {t.a_t1 - q.t1, t.b_t1 - t.a_t1, t.c_t1 - t.a_t1});
      const bool certain = ccd::detail::certified_sign(own.coefficients, own.error_upper);
      const bool lane_settled = ((got.settled >> k) & 1u) != 0;
      ASSERT_EQ(lane_settled, certain) << "batch " << batch << " lane " << k;
      if (!lane_settled) {
        ++unsettled;
        continue;
      }
      ++settled;
      const OrientationClass c = classify(t, q);
      ASSERT_EQ(got.classes[k], c) << "batch " << batch << " lane " << k;
      (c == OrientationClass::positive ? positives : negatives)++;
    }
  }
  EXPECT_GT(positives, 500);
  EXPECT_GT(negatives, 500);
  EXPECT_GT(unsettled, 200);
  EXPECT_GT(settled, 2000);
}

// The segment observers' four at a time: a lane is settled exactly when both endpoints' screens
// are certain with one sign, and then its class is classify's.
TEST(OrientationClass, FourSegmentClassesAtOnceAreClassifysBitForBit) {
  std::mt19937_64 rng(977);
  int settled = 0, unsettled = 0;
  for (int batch = 0; batch < 1500; ++batch) {
    std::array<MovingTriangle, 4> tris;
    for (auto& t : tris) t = random_triangle(rng);
    const double reach = batch % 3 == 0 ? 0.5 : 3.0;
    MovingSegment q;
    q.q1_t0 = random_point(rng, reach);
    q.q2_t0 = q.q1_t0 + random_point(rng, 0.5);
    q.q1_t1 = q.q1_t0 + random_point(rng, 0.2);
    q.q2_t1 = q.q2_t0 + random_point(rng, 0.2);
    ccd::FaceCorners c0{}, c1{};
    for (std::size_t k = 0; k < 4; ++k) {
      c0[k] = {tris[k].a_t0.data(), tris[k].b_t0.data(), tris[k].c_t0.data()};
      c1[k] = {tris[k].a_t1.data(), tris[k].b_t1.data(), tris[k].c_t1.data()};
    }
    const ScreenedClasses got = screen_classes_x4(c0, c1, q);
    for (std::size_t k = 0; k < 4; ++k) {
      const MovingTriangle& t = tris[k];
      int signs[2] = {0, 0};
      for (int e = 0; e < 2; ++e) {
        const V3& p0 = e == 0 ? q.q1_t0 : q.q2_t0;
        const V3& p1 = e == 0 ? q.q1_t1 : q.q2_t1;
        const ccd::detail::TrilinearScreen own = ccd::detail::trilinear_screen(
            {t.a_t0 - p0, t.b_t0 - t.a_t0, t.c_t0 - t.a_t0},
            {t.a_t1 - p1, t.b_t1 - t.a_t1, t.c_t1 - t.a_t1});
        if (ccd::detail::certified_sign(own.coefficients, own.error_upper)) {
          signs[e] = own.coefficients[0] > 0.0 ? 1 : -1;
        }
      }
      const bool lane_settled = ((got.settled >> k) & 1u) != 0;
      ASSERT_EQ(lane_settled, signs[0] != 0 && signs[0] == signs[1]) << batch << " " << k;
      if (!lane_settled) {
        ++unsettled;
        continue;
      }
      ++settled;
      ASSERT_EQ(got.classes[k], classify(t, q)) << "batch " << batch << " lane " << k;
    }
  }
  EXPECT_GT(settled, 1500);
  EXPECT_GT(unsettled, 500);
}

TEST(OrientationClass, PointClassesNearTangency) {
  // Observers placed so that f has a double root near [0,1]: an observer passing close to the
  // plane at mid-interval. Proven classes must still hold at every sample.
  std::mt19937_64 rng(7);
  int proven = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const MovingTriangle tri = random_triangle(rng);
    const V3 n = (tri.b_t0 - tri.a_t0).cross(tri.c_t0 - tri.a_t0).normalized();
    std::uniform_real_distribution<double> u(-1e-3, 1e-3);
    const V3 near_plane = tri.a_t0 + 0.5 * (tri.b_t0 - tri.a_t0) + u(rng) * n;
    const MovingPoint q{near_plane + 0.2 * n, near_plane + 0.2 * n + random_point(rng, 0.3)};
    const OrientationClass c = classify(tri, q);
    if (c == OrientationClass::uncertain) continue;
    ++proven;
    const int expected = c == OrientationClass::positive ? 1 : -1;
    for (int k = 0; k <= kSamples; ++k) {
      ASSERT_EQ(exact_point_sign(tri, q, mpq_class(k, kSamples)), expected) << "trial " << trial;
    }
  }
  EXPECT_GT(proven, 25);
}

TEST(OrientationClass, LineClassesHoldAtEveryPointAndSample) {
  std::mt19937_64 rng(99);
  int positives = 0;
  int negatives = 0;
  int beyond_endpoints = 0;  // proven where the two endpoints disagree
  const std::array<std::array<mpq_class, 3>, 7> barys{{
      {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
      {mpq_class(1, 3), mpq_class(1, 3), mpq_class(1, 3)},
      {mpq_class(1, 2), mpq_class(1, 2), 0}, {0, mpq_class(1, 2), mpq_class(1, 2)},
      {mpq_class(1, 10), mpq_class(7, 10), mpq_class(1, 5)},
  }};
  for (int trial = 0; trial < 600; ++trial) {
    const MovingTriangle tri = random_triangle(rng);
    // A bone-like segment below the triangle, each end moving on its own.
    const V3 base = random_point(rng, 1.5);
    const V3 axis = random_point(rng, 2.0);
    const MovingSegment s{base, base + axis, base + random_point(rng, 0.3),
                          base + axis + random_point(rng, 0.3)};
    const OrientationClass c = classify(tri, s);
    if (c == OrientationClass::uncertain) continue;
    (c == OrientationClass::positive ? positives : negatives)++;
    const auto c1 = classify(tri, MovingPoint{s.q1_t0, s.q1_t1});
    const auto c2 = classify(tri, MovingPoint{s.q2_t0, s.q2_t1});
    if (c1 != c || c2 != c) ++beyond_endpoints;
    const int expected = c == OrientationClass::positive ? 1 : -1;
    for (int k = 0; k <= kSamples; k += 8) {
      for (const auto& bary : barys) {
        ASSERT_EQ(exact_line_sign(tri, s, mpq_class(k, kSamples), bary), expected)
            << "trial " << trial << " t = " << k << "/" << kSamples;
      }
    }
  }
  EXPECT_GT(positives, 40);
  EXPECT_GT(negatives, 40);
  EXPECT_GT(beyond_endpoints, 5);
}

TEST(OrientationClass, ProjectionRangeEnclosesTheExactParameter) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 200; ++trial) {
    const MovingTriangle tri = random_triangle(rng);
    const V3 base = random_point(rng, 1.5);
    const V3 axis = random_point(rng, 2.0);
    const MovingSegment s{base, base + axis, base + random_point(rng, 0.5),
                          base + axis + random_point(rng, 0.5)};
    const ProjectionRange r = projection_range(tri, s);
    ASSERT_LE(0.0, r.lo);
    ASSERT_LE(r.lo, r.hi);
    ASSERT_LE(r.hi, 1.0);
    const ExactTriangle et(tri);
    for (int k = 0; k <= kSamples; k += 3) {
      const mpq_class t(k, kSamples);
      const auto p = et.at(t);
      const Q3 q1 = lerp(exact(s.q1_t0), exact(s.q1_t1), t);
      const Q3 d = sub(lerp(exact(s.q2_t0), exact(s.q2_t1), t), q1);
      const mpq_class dd = dot(d, d);
      ASSERT_GT(dd, 0);
      for (const auto& x : p) {
        mpq_class sigma = dot(sub(x, q1), d) / dd;
        if (sigma < 0) sigma = 0;
        if (sigma > 1) sigma = 1;
        ASSERT_LE(mpq_class(r.lo), sigma) << "trial " << trial;
        ASSERT_GE(mpq_class(r.hi), sigma) << "trial " << trial;
      }
    }
  }
}

}  // namespace
}  // namespace skelcd::clustering
