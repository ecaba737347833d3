// The exact winding number in front of a triangle (clustering/side_winding.hpp) against a
// floating-point reference — the solid angles of every triangle seen from a point in front of it,
// summed (generalized winding number), compared only where that point is far enough from the
// surface for the sum to round cleanly — on overlapping, nested and inside-out closed surfaces.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <vector>

#include "clustering/side_winding.hpp"
#include "tests/segmentation/mini_rigs.hpp"

namespace skelcd::clustering {
namespace {

using V3 = Eigen::Vector3d;
using test::MeshData;

V3 row(const MeshData& m, Eigen::Index v) { return m.V.row(v).transpose(); }

/// Generalized winding number at p (sum of signed solid angles / 4π; Van Oosterom–Strackee).
double winding_reference(const MeshData& m, const V3& p) {
  double sum = 0.0;
  for (Eigen::Index t = 0; t < m.F.rows(); ++t) {
    const V3 a = row(m, m.F(t, 0)) - p;
    const V3 b = row(m, m.F(t, 1)) - p;
    const V3 c = row(m, m.F(t, 2)) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2.0 * std::atan2(num, den);
  }
  return sum / (4.0 * std::numbers::pi);
}

std::vector<std::int32_t> all_triangles(const MeshData& m) {
  std::vector<std::int32_t> ids(static_cast<std::size_t>(m.F.rows()));
  std::iota(ids.begin(), ids.end(), 0);
  return ids;
}

MeshData moved(MeshData m, const V3& offset, double scale = 1.0) {
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) {
    m.V.row(v) = (scale * row(m, v) + offset).transpose();
  }
  return m;
}

MeshData flipped(MeshData m) {
  for (Eigen::Index t = 0; t < m.F.rows(); ++t) std::swap(m.F(t, 1), m.F(t, 2));
  return m;
}

/// Every triangle's value within a few attempts (−999: undecided, which fails the test unless
/// `may_miss`: where surfaces cross, the short segment of a triangle cut by another may meet it).
std::vector<int> winding_of_every_triangle(const MeshData& m, bool may_miss = false) {
  const auto ids = all_triangles(m);
  const culling::Aabb box = surface_box(ids, m.F, m.V);
  std::vector<int> values;
  int undecided_first = 0;
  for (const std::int32_t f : ids) {
    std::optional<int> w;
    for (int attempt = 0; attempt < 6 && !w; ++attempt) {
      w = front_winding(ids, box, m.F, m.V, f, attempt);
      if (!w && attempt == 0) ++undecided_first;
    }
    EXPECT_TRUE(may_miss || w.has_value()) << "triangle " << f;
    values.push_back(w.value_or(-999));
  }
  // Generic closed surfaces: the first ray almost always decides.
  EXPECT_LE(undecided_first, static_cast<int>(ids.size()) / 20);
  return values;
}

/// Compares with the reference at the exact method's front point's neighbourhood: a point a
/// little further in front of the centroid (where the reference is clean).
void expect_matches_reference(const MeshData& m, const std::vector<int>& values, int& compared) {
  for (Eigen::Index t = 0; t < m.F.rows(); ++t) {
    const V3 a = row(m, m.F(t, 0)), b = row(m, m.F(t, 1)), c = row(m, m.F(t, 2));
    const V3 n = (b - a).cross(c - a);
    const V3 p = (a + b + c) / 3.0 + 1e-3 * std::sqrt(n.norm()) * n.normalized();
    const double ref = winding_reference(m, p);
    if (std::abs(ref - std::round(ref)) > 0.02) continue;       // too close to another sheet
    if (values[static_cast<std::size_t>(t)] == -999) continue;  // undecided (may_miss)
    ++compared;
    EXPECT_EQ(values[static_cast<std::size_t>(t)], static_cast<int>(std::lround(ref)))
        << "triangle " << t;
  }
}

TEST(SideWinding, EmbeddedOutwardSurfaceIsZeroInFront) {
  const MeshData sphere = test::icosphere(2);
  for (const int w : winding_of_every_triangle(sphere)) EXPECT_EQ(w, 0);
  const MeshData tube = test::closed_tube(3.0, 0.4, 12, 10, 0.3);
  int compared = 0;
  expect_matches_reference(tube, winding_of_every_triangle(tube), compared);
  EXPECT_EQ(compared, tube.F.rows());
}

TEST(SideWinding, InsideOutSurfaceIsMinusOneInFront) {
  for (const int w : winding_of_every_triangle(flipped(test::icosphere(2)))) EXPECT_EQ(w, -1);
}

TEST(SideWinding, NestedSurfaceSeesTheOuterOne) {
  const MeshData outer = test::icosphere(2, 2.0);
  const MeshData inner = moved(test::icosphere(1), V3(0.2, -0.1, 0.15), 0.5);
  const MeshData both = test::concat(outer, inner);
  const auto values = winding_of_every_triangle(both);
  for (Eigen::Index t = 0; t < both.F.rows(); ++t) {
    EXPECT_EQ(values[static_cast<std::size_t>(t)], t < outer.F.rows() ? 0 : 1);
  }
}

TEST(SideWinding, OverlappingSurfacesMatchTheSolidAngleSum) {
  // Two spheres (and a tube through them) that overlap: the skin of one inside the other has
  // winding number 1 in front, the rest 0; where three overlap, 2.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  int compared = 0, inside = 0;
  for (int trial = 0; trial < 6; ++trial) {
    const MeshData a = test::icosphere(2);
    const MeshData b = moved(test::icosphere(2), V3(1.0 + u(rng), u(rng), u(rng)), 0.9);
    const MeshData c = moved(test::closed_tube(3.0, 0.35, 10, 9, 0.2), V3(-1.0, u(rng), u(rng)));
    const MeshData all = test::concat(test::concat(a, b), c);
    const auto values = winding_of_every_triangle(all, /*may_miss=*/true);
    expect_matches_reference(all, values, compared);
    for (const int w : values) inside += w > 0 ? 1 : 0;
  }
  EXPECT_GT(compared, 3000);
  EXPECT_GT(inside, 300);  // the overlaps are really there
}

TEST(SideWinding, UndecidableAttemptsSayNothing) {
  MeshData sphere = test::icosphere(1);
  const auto ids = all_triangles(sphere);
  // A degenerate triangle: no normal, no answer.
  MeshData flat = sphere;
  flat.V.row(flat.F(0, 1)) = flat.V.row(flat.F(0, 0));
  EXPECT_FALSE(
      front_winding(ids, surface_box(ids, flat.F, flat.V), flat.F, flat.V, 0, 0).has_value());
  // A second sheet within the short segment in front of triangle 0: the segment meets it.
  const V3 a = row(sphere, sphere.F(0, 0)), b = row(sphere, sphere.F(0, 1)),
           c = row(sphere, sphere.F(0, 2));
  const V3 n = (b - a).cross(c - a).normalized();
  const MeshData close_shell = moved(sphere, 1e-6 * n);
  const MeshData both = test::concat(sphere, close_shell);
  const auto both_ids = all_triangles(both);
  const culling::Aabb both_box = surface_box(both_ids, both.F, both.V);
  for (int attempt = 0; attempt < 3; ++attempt) {
    EXPECT_FALSE(front_winding(both_ids, both_box, both.F, both.V, 0, attempt).has_value());
  }
  // An axis-aligned box (coplanar faces, edges along the axes): the tilted rays decide.
  MeshData box = test::from_lists(
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
      {{0, 2, 1},
       {0, 3, 2},
       {4, 5, 6},
       {4, 6, 7},
       {0, 1, 5},
       {0, 5, 4},
       {1, 2, 6},
       {1, 6, 5},
       {2, 3, 7},
       {2, 7, 6},
       {3, 0, 4},
       {3, 4, 7}});
  for (const int w : winding_of_every_triangle(box)) EXPECT_EQ(w, 0);
}

}  // namespace
}  // namespace skelcd::clustering
