// The filtered orient3d against the exact rational reference, on easy, coplanar and
// nearly-coplanar input.

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "segmentation/detail/orient3d.hpp"

namespace {

using skelcd::segmentation::detail::orient3d_sign;
using skelcd::segmentation::detail::orient3d_sign_exact;
using V3 = Eigen::Vector3d;

TEST(Orient3d, SignConventionMatchesTheObserverTest) {
  // Triangle in z = 0, counter-clockwise seen from +z: normal +z. An observer below (inside, if
  // +z is outward) sees it positively: (p − q) · n > 0.
  const V3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(orient3d_sign(a, b, c, V3(0.2, 0.2, -1)), 1);
  EXPECT_EQ(orient3d_sign(a, b, c, V3(0.2, 0.2, 1)), -1);
  EXPECT_EQ(orient3d_sign(a, b, c, V3(5, -3, 0)), 0);
  EXPECT_EQ(orient3d_sign(a, a, c, V3(5, -3, 1)), 0);  // degenerate triangle
}

TEST(Orient3d, AgreesWithExactOnRandomPoints) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20000; ++k) {
    const V3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng)),
        d(u(rng), u(rng), u(rng));
    ASSERT_EQ(orient3d_sign(a, b, c, d), orient3d_sign_exact(a, b, c, d)) << k;
  }
}

TEST(Orient3d, AgreesWithExactOnNearlyCoplanarPoints) {
  // d on the plane of abc up to rounding (and nudged by {−1, 0, +1} ulps), at scales 1e-6 … 1e6.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int zeros = 0, nonzero = 0;
  for (const double scale : {1e-6, 1.0, 1e6}) {
    for (int k = 0; k < 3000; ++k) {
      const V3 a = scale * V3(u(rng), u(rng), u(rng));
      const V3 b = scale * V3(u(rng), u(rng), u(rng));
      const V3 c = scale * V3(u(rng), u(rng), u(rng));
      V3 d = a + u(rng) * (b - a) + u(rng) * (c - a);
      for (const int nudge : {-1, 0, 1}) {
        V3 e = d;
        if (nudge != 0) e.z() = std::nextafter(d.z(), nudge * std::numeric_limits<double>::infinity());
        const int exact = orient3d_sign_exact(a, b, c, e);
        ASSERT_EQ(orient3d_sign(a, b, c, e), exact) << scale << " " << k;
        (exact == 0 ? zeros : nonzero)++;
      }
    }
  }
  EXPECT_GT(nonzero, 0);
  // Exactly coplanar cases built on representable grids.
  for (int k = 0; k < 1000; ++k) {
    const auto g = [&] { return std::round(u(rng) * 64.0) / 8.0; };
    const V3 a(g(), g(), 0.5), b(g(), g(), 0.5), c(g(), g(), 0.5), d(g(), g(), 0.5);
    ASSERT_EQ(orient3d_sign(a, b, c, d), 0);
  }
}

}  // namespace
