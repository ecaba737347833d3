// Orientation of a triangle to an observer (the sign convention of §3.1, and exactness against a
// rational evaluation of (a − q) · ((b − a) × (c − a)) on easy and nearly coplanar input).

#include <cmath>
#include <limits>
#include <random>

#include <gmpxx.h>
#include <gtest/gtest.h>

#include "segmentation/observer.hpp"

namespace {

using namespace skelcd::segmentation;
using V3 = Eigen::Vector3d;

Observer point_at(const V3& q) { return Observer{ObserverKind::point, {q, q}}; }

int exact_sign(const V3& a, const V3& b, const V3& c, const V3& q) {
  const auto r = [](double x) { return mpq_class(x); };
  const mpq_class nx = (r(b.y()) - a.y()) * (r(c.z()) - a.z()) - (r(b.z()) - a.z()) * (r(c.y()) - a.y());
  const mpq_class ny = (r(b.z()) - a.z()) * (r(c.x()) - a.x()) - (r(b.x()) - a.x()) * (r(c.z()) - a.z());
  const mpq_class nz = (r(b.x()) - a.x()) * (r(c.y()) - a.y()) - (r(b.y()) - a.y()) * (r(c.x()) - a.x());
  return sgn((r(a.x()) - q.x()) * nx + (r(a.y()) - q.y()) * ny + (r(a.z()) - q.z()) * nz);
}

int sign_of(Orientation o) { return static_cast<int>(o); }

TEST(Orientation, SignConventionOfSection31) {
  // Triangle in z = 0, counter-clockwise seen from +z (outward normal +z): an observer below it
  // (inside) sees its back — positively oriented; above it, negatively; in its plane, uncertain.
  const V3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(orientation(point_at(V3(0.2, 0.2, -1)), a, b, c), Orientation::positive);
  EXPECT_EQ(orientation(point_at(V3(0.2, 0.2, 1)), a, b, c), Orientation::negative);
  EXPECT_EQ(orientation(point_at(V3(5, -3, 0)), a, b, c), Orientation::uncertain);
  EXPECT_EQ(orientation(point_at(V3(5, -3, 1)), a, a, c), Orientation::uncertain);  // degenerate
  // A line observer views from a's projection onto it. A sloped wall (normal (1, 0, 1)) and the
  // segment z ∈ [−1, 3] on the z axis: a = (1, 0, 0) projects to the origin, behind the wall;
  // the midpoint (0, 0, 1) lies in the wall's plane.
  const V3 wa(1, 0, 0), wb(1, 1, 0), wc(0, 0, 1);
  const BoneSegment axis{V3(0, 0, -1), V3(0, 0, 3)};
  EXPECT_EQ(Observer({ObserverKind::line, axis}).viewing_position(wa), V3(0, 0, 0));
  EXPECT_EQ(orientation(Observer{ObserverKind::line, axis}, wa, wb, wc), Orientation::positive);
  EXPECT_EQ(orientation(Observer{ObserverKind::point, axis}, wa, wb, wc), Orientation::uncertain);
}

TEST(Orientation, ExactOnRandomAndNearlyCoplanarInput) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int zeros = 0;
  for (const double scale : {1e-6, 1.0, 1e6}) {
    for (int k = 0; k < 3000; ++k) {
      const V3 a = scale * V3(u(rng), u(rng), u(rng));
      const V3 b = scale * V3(u(rng), u(rng), u(rng));
      const V3 c = scale * V3(u(rng), u(rng), u(rng));
      // Random observers, and observers on the plane of abc up to rounding, nudged by an ulp.
      const V3 on_plane = a + u(rng) * (b - a) + u(rng) * (c - a);
      for (int nudge = -2; nudge <= 1; ++nudge) {
        V3 q = nudge == -2 ? scale * V3(u(rng), u(rng), u(rng)) : on_plane;
        if (nudge == -1 || nudge == 1) {
          q.z() = std::nextafter(q.z(), nudge * std::numeric_limits<double>::infinity());
        }
        const int exact = exact_sign(a, b, c, q);
        zeros += exact == 0;
        ASSERT_EQ(sign_of(orientation(point_at(q), a, b, c)), exact) << scale << " " << k;
      }
    }
  }
  // Exactly coplanar observers on a representable grid.
  for (int k = 0; k < 1000; ++k) {
    const auto g = [&] { return std::round(u(rng) * 64.0) / 8.0; };
    const V3 a(g(), g(), 0.5), b(g(), g(), 0.5), c(g(), g(), 0.5), q(g(), g(), 0.5);
    ASSERT_EQ(orientation(point_at(q), a, b, c), Orientation::uncertain);
  }
}

}  // namespace
