// Vertex fans (culling/vertex_fans.hpp): which vertices have one, that a certified fan never has
// two intersecting triangles (against the exact triangle test, on random and folded fans), and
// that DCD with fans reports exactly the pairs it reports testing every pair, on real characters.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "ccd/orientation.hpp"
#include "ccd/triangle_triangle.hpp"
#include "culling/feature_topology.hpp"
#include "culling/method.hpp"
#include "culling/vertex_fans.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/culling/renamed_kernels.hpp"
#include "tests/culling/welded_character.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

using Tri = std::array<std::int32_t, 3>;

/// A fan around vertex 0 with spokes 1..m; closed joins spoke m back to spoke 1.
std::vector<Tri> fan(int m, bool closed) {
  std::vector<Tri> t;
  for (int i = 1; i < m; ++i) t.push_back({0, i, i + 1});
  if (closed) t.push_back({0, m, 1});
  return t;
}

skinning::Positions positions(const std::vector<Eigen::Vector3d>& p) {
  skinning::Positions x(static_cast<Eigen::Index>(p.size()), 3);
  for (std::size_t i = 0; i < p.size(); ++i) x.row(static_cast<Eigen::Index>(i)) = p[i].transpose();
  return x;
}

/// Spoke i at angle angles[i] (radians) around the z axis, height heights[i].
std::vector<Eigen::Vector3d> star(
    const std::vector<double>& angles, const std::vector<double>& heights) {
  std::vector<Eigen::Vector3d> p{Eigen::Vector3d::Zero()};
  for (std::size_t i = 0; i < angles.size(); ++i) {
    p.emplace_back(std::cos(angles[i]), std::sin(angles[i]), heights[i]);
  }
  return p;
}

/// The triangles of v's fan (v, spoke i, spoke i + 1), as VertexFans::spokes gives them.
std::vector<Tri> fan_of(const VertexFans& fans, std::int32_t v) {
  const auto s = fans.spokes(v);
  std::vector<Tri> t;
  const std::size_t m = fans.closed(v) ? s.size() : s.size() - 1;
  for (std::size_t i = 0; i < m; ++i) t.push_back({v, s[i], s[(i + 1) % s.size()]});
  return t;
}

/// Does any pair of the triangles intersect beyond the corners they share (the exact test)?
bool some_pair_intersects(const std::vector<Tri>& tris, const skinning::Positions& x) {
  const auto row = [&](std::int32_t i) { return Eigen::Vector3d(x.row(i).transpose()); };
  for (std::size_t a = 0; a < tris.size(); ++a) {
    for (std::size_t b = a + 1; b < tris.size(); ++b) {
      ccd::SharedCorners shared = ccd::kNoSharedCorners;
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          if (tris[a][static_cast<std::size_t>(i)] == tris[b][static_cast<std::size_t>(j)]) {
            shared[static_cast<std::size_t>(i)] = static_cast<std::int8_t>(j);
          }
        }
      }
      const ccd::TriangleTriangleQuery q{
          row(tris[a][0]),
          row(tris[a][1]),
          row(tris[a][2]),
          row(tris[b][0]),
          row(tris[b][1]),
          row(tris[b][2])};
      if (ccd::triangles_intersect(q, shared)) return true;
    }
  }
  return false;
}

TEST(VertexFans, ClosedOpenAndNoFan) {
  // A closed fan of 5 around vertex 0: spokes in order; each spoke an open fan of 2 triangles.
  const VertexFans closed(fan(5, true), 6);
  EXPECT_EQ(closed.num_fans(), 6);
  ASSERT_EQ(closed.spokes(0).size(), 5u);
  EXPECT_TRUE(closed.closed(0));
  EXPECT_EQ(closed.spokes(0)[0], 1);
  EXPECT_EQ(closed.spokes(0)[4], 5);
  EXPECT_FALSE(closed.closed(1));
  // The open fan 1..5 around vertex 0: a path of 5 spokes for 4 triangles.
  const VertexFans open(fan(5, false), 6);
  ASSERT_EQ(open.spokes(0).size(), 5u);
  EXPECT_FALSE(open.closed(0));
  // A flipped triangle (inconsistent orientation), a duplicate face, a degenerate triangle, and
  // a bow tie (two fans through one vertex): no fan at vertex 0.
  auto flipped = fan(5, true);
  std::swap(flipped[2][1], flipped[2][2]);
  EXPECT_TRUE(VertexFans(flipped, 6).spokes(0).empty());
  auto duplicate = fan(5, true);
  duplicate.push_back(duplicate[0]);
  EXPECT_TRUE(VertexFans(duplicate, 6).spokes(0).empty());
  auto degenerate = fan(5, true);
  degenerate.push_back({0, 1, 1});
  EXPECT_TRUE(VertexFans(degenerate, 6).spokes(0).empty());
  std::vector<Tri> bow_tie{{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {0, 4, 5}, {0, 5, 6}, {0, 6, 4}};
  EXPECT_TRUE(VertexFans(bow_tie, 7).spokes(0).empty());
  EXPECT_FALSE(VertexFans(bow_tie, 7).spokes(4).empty());
}

TEST(VertexFans, ChainsFansOfAnySizeFromShuffledTriangles) {
  // Fans of 1 to 40 triangles, their triangles shuffled and their spokes relabelled at random: a
  // closed fan's spokes start at its smallest label and follow the triangles' orientation, an open
  // one's at its free start; and a flipped triangle, a duplicate face or a second fan through the
  // vertex leaves no fan.
  std::mt19937 rng(5);
  for (int m = 1; m <= 40; ++m) {
    for (const bool closed : {false, true}) {
      if (closed && m < 3) continue;
      // Spoke i (1 … m, or m + 1 open) gets label labels[i]; vertex 0 stays 0.
      const int spokes = closed ? m : m + 1;
      std::vector<std::int32_t> labels(static_cast<std::size_t>(spokes) + 1);
      for (int i = 0; i <= spokes; ++i) labels[static_cast<std::size_t>(i)] = i;
      std::shuffle(labels.begin() + 1, labels.end(), rng);
      std::vector<Tri> tris;
      for (int i = 1; i <= m; ++i) {
        const int j = i == spokes ? 1 : i + 1;  // closed: spoke m back to spoke 1
        tris.push_back(
            {0, labels[static_cast<std::size_t>(i)], labels[static_cast<std::size_t>(j)]});
      }
      std::shuffle(tris.begin(), tris.end(), rng);
      const auto name = std::to_string(m) + (closed ? " closed" : " open");
      SCOPED_TRACE(name);
      const VertexFans fans(tris, spokes + 1);
      ASSERT_EQ(fans.closed(0), closed);
      const auto got = fans.spokes(0);
      ASSERT_EQ(got.size(), static_cast<std::size_t>(spokes));
      // Expected: rotate the cycle to its smallest label; a path from spoke 1.
      std::size_t first = 1;
      if (closed) {
        for (int i = 1; i <= spokes; ++i) {
          if (labels[static_cast<std::size_t>(i)] < labels[first])
            first = static_cast<std::size_t>(i);
        }
      }
      for (int k = 0; k < spokes; ++k) {
        const std::size_t i =
            (first - 1 + static_cast<std::size_t>(k)) % static_cast<std::size_t>(spokes) + 1;
        EXPECT_EQ(got[static_cast<std::size_t>(k)], labels[i]) << "spoke " << k;
      }
      if (m >= 2) {
        auto flipped = tris;
        std::swap(flipped[0][1], flipped[0][2]);
        EXPECT_TRUE(VertexFans(flipped, spokes + 1).spokes(0).empty()) << "flipped";
      }
      auto duplicate = tris;
      duplicate.push_back(tris[0]);
      EXPECT_TRUE(VertexFans(duplicate, spokes + 1).spokes(0).empty()) << "duplicate";
      // A second closed fan of three through vertex 0, on spokes of its own.
      auto bow_tie = tris;
      for (int i = 0; i < 3; ++i) bow_tie.push_back({0, spokes + 1 + i, spokes + 1 + (i + 1) % 3});
      EXPECT_TRUE(VertexFans(bow_tie, spokes + 4).spokes(0).empty()) << "bow tie";
    }
  }
}

TEST(VertexFans, CertifiesFlatAndBumpyFansAndRefusesOnesThatWindTwice) {
  const auto tris = fan(5, true);
  const VertexFans fans(tris, 6);
  const double step = 2.0 * std::numbers::pi / 5.0;
  // Flat (exactly coplanar in z = 0) and bumpy: certified, and indeed no pair meets.
  for (const double h : {0.0, 0.3}) {
    const auto x = positions(star({0, step, 2 * step, 3 * step, 4 * step}, {h, -h, h, -h, 0}));
    EXPECT_TRUE(fans.certified(x, 0)) << h;
    EXPECT_FALSE(some_pair_intersects(tris, x));
  }
  // Winding twice (each sector 144°): every projected triangle has the same orientation, yet the
  // fan overlaps itself — not certified, and the exact test finds intersecting pairs.
  const double twice = 2.0 * step;
  const auto x = positions(star({0, twice, 2 * twice, 3 * twice, 4 * twice}, {0, 0, 0, 0, 0}));
  EXPECT_FALSE(fans.certified(x, 0));
  EXPECT_TRUE(some_pair_intersects(tris, x));
  // An open fan sweeping more than a full turn (five sectors of 80°): not certified.
  const auto open_tris = fan(6, false);
  const VertexFans open(open_tris, 7);
  const double s80 = 80.0 * std::numbers::pi / 180.0;
  const auto xo =
      positions(star({0, s80, 2 * s80, 3 * s80, 4 * s80, 5 * s80}, {0, 0.1, 0.2, 0.3, 0.4, 0.5}));
  EXPECT_FALSE(open.certified(xo, 0));
  // The same open fan over 4 sectors of 80° (320°): certified.
  const auto open4 = fan(5, false);
  const auto x4 = positions(star({0, s80, 2 * s80, 3 * s80, 4 * s80}, {0, 0.1, 0.2, 0.1, 0}));
  EXPECT_TRUE(VertexFans(open4, 6).certified(x4, 0));
}

// A closed fan's winding is counted on the direction (1, 0) of its coordinate projection, from
// coordinate signs: spokes exactly opposite each other (orient = 0, which the first spoke's ray
// could not decide) or exactly on that direction are certified when the fan winds once, and a
// fan winding twice with a spoke on it is still refused.
TEST(VertexFans, ClosedFansWithSpokesOnTheCountingDirectionAreDecidedExactly) {
  const VertexFans square(fan(4, true), 5);
  // A flat quad-grid vertex: spokes at 0°, 90°, 180°, 270° (exact coordinates), and a bumpy one.
  const std::vector<Eigen::Vector3d> flat{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}};
  const std::vector<Eigen::Vector3d> bumpy{
      {0, 0, 0}, {1, 0, 0.25}, {0, 1, -0.25}, {-1, 0, 0.25}, {0, -1, -0.25}};
  for (const auto& p : {flat, bumpy}) {
    const auto x = positions(p);
    EXPECT_TRUE(square.certified(x, 0));
    EXPECT_FALSE(some_pair_intersects(fan(4, true), x));
    EXPECT_TRUE(square.certified_over(x, x, 0));
  }
  // Six flat spokes, (1, 0), (-1, 1), (-1, -1) and twice as far the same way round: every sector
  // strictly oriented, the fan winding twice, spokes 1 and 4 on (1, 0).
  const VertexFans six(fan(6, true), 7);
  const auto twice = positions(
      {{0, 0, 0}, {1, 0, 0}, {-1, 1, 0}, {-1, -1, 0}, {2, 0, 0}, {-2, 2, 0}, {-2, -2, 0}});
  EXPECT_FALSE(six.certified(twice, 0));
  EXPECT_TRUE(some_pair_intersects(fan(6, true), twice));
}

// Random fans, closed and open, from nearly flat to wildly folded: a certified one never has an
// intersecting pair (the exact test decides), and both outcomes occur often.
TEST(VertexFans, CertifiedFansNeverIntersectThemselves) {
  std::mt19937_64 rng(1234);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> spokes(3, 9);
  int certified = 0, refused = 0, refused_and_intersecting = 0;
  for (int n = 0; n < 3000; ++n) {
    const int m = spokes(rng);
    const bool closed = n % 2 == 0;
    const auto tris = fan(m, closed);
    // Angles increasing by random steps (sometimes exceeding a full turn), random heights and
    // radii, and a random rotation: the projection axis differs from case to case.
    const double spread = (n % 5 == 0) ? 4.0 : 2.0;
    std::vector<Eigen::Vector3d> p{Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 0.1};
    double angle = 0;
    const double bump = (n % 3 == 0) ? 0.0 : std::abs(unit(rng)) * 2.0;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(
            unit(rng) * 3.0, Eigen::Vector3d(unit(rng), unit(rng), unit(rng) + 2).normalized())
            .toRotationMatrix();
    for (int i = 0; i < m; ++i) {
      const double radius = 0.2 + std::abs(unit(rng));
      p.push_back(
          r *
          Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), bump * unit(rng)));
      angle += spread * std::numbers::pi / m * (0.3 + std::abs(unit(rng)));
    }
    const auto x = positions(p);
    const VertexFans fans(tris, m + 1);
    ASSERT_FALSE(fans.spokes(0).empty());
    if (fans.certified(x, 0)) {
      ++certified;
      ASSERT_FALSE(some_pair_intersects(tris, x)) << "case " << n;
    } else {
      ++refused;
      refused_and_intersecting += some_pair_intersects(tris, x) ? 1 : 0;
    }
  }
  EXPECT_GT(certified, 500);
  EXPECT_GT(refused, 300);
  EXPECT_GT(refused_and_intersecting, 100);
}

/// VertexFans::certified as it was before it took the spokes' differences once and before it tried
/// the fan's own normal (every sign through ccd::detail::cross_component_static on the points, in
/// the coordinate projection only): what the certificate must still accept.
bool certified_two_signs_per_sector(
    const VertexFans& fans, const skinning::Positions& x, std::int32_t v) {
  const std::span<const std::int32_t> s = fans.spokes(v);
  const bool closed = fans.closed(v);
  const std::size_t m = closed ? s.size() : (s.empty() ? 0 : s.size() - 1);
  if (m < (closed ? 3u : 1u)) return false;
  const auto point = [&](std::int32_t i) { return Eigen::Vector3d(x(i, 0), x(i, 1), x(i, 2)); };
  const auto spoke = [&](std::size_t i) { return point(s[i % s.size()]); };
  const Eigen::Vector3d c = point(v);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < m; ++i) n += (spoke(i) - c).cross(spoke(i + 1) - c);
  int k = 0;
  if (std::abs(n.y()) > std::abs(n[k])) k = 1;
  if (std::abs(n.z()) > std::abs(n[k])) k = 2;
  const int i_axis = (k + 1) % 3;
  const int j_axis = (k + 2) % 3;
  const auto orient = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
    return ccd::detail::cross_component_static(c, p, q, i_axis, j_axis);
  };
  const Eigen::Vector3d r = spoke(0);
  int sign = 0;
  int covering = 0;
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Vector3d a = spoke(i);
    const Eigen::Vector3d b = spoke(i + 1);
    const int o = orient(a, b);
    if (o == ccd::detail::kUndecided) return false;
    if (sign == 0) sign = o;
    if (o != sign) return false;
    if (i == 0) {
      ++covering;
    } else if (!closed || i + 1 < m) {
      const int o1 = orient(a, r);
      const int o2 = orient(r, b);
      if (o1 == ccd::detail::kUndecided || o2 == ccd::detail::kUndecided) return false;
      if (o1 == sign && o2 == sign) ++covering;
    }
  }
  return covering == 1;
}

// The certificate from the spokes' differences taken once accepts every fan the filter on the
// points accepts in the coordinate projection, and each fan it accepts beyond those (seen along
// its own normal) has no intersecting pair by the exact test: on random fans, on lattice fans
// whose spokes fall exactly on the ray or on each other (undecided signs), on fans of 40 spokes
// (past the stack buffer), and on every vertex of real characters, where the normal certifies
// many more.
TEST(VertexFans, DifferencesTakenOnceKeepTheAxisCertificatesAndTheNormalOnesAreSound) {
  std::mt19937_64 rng(99);
  std::uniform_int_distribution<int> lattice(-2, 2);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> spokes(3, 9);
  int certified = 0, refused = 0, by_normal = 0;
  for (int n = 0; n < 20000; ++n) {
    const int m = n % 50 == 1 ? 40 : spokes(rng);
    const bool closed = n % 2 == 0;
    const auto tris = fan(m, closed);
    std::vector<Eigen::Vector3d> p{Eigen::Vector3d::Zero()};
    double angle = 0;
    for (int i = 0; i < m; ++i) {
      if (n % 3 == 0) {  // a small lattice: exact zeros and repeated directions are common
        p.emplace_back(lattice(rng), lattice(rng), lattice(rng) * 0.25);
      } else {
        const double radius = 0.2 + std::abs(unit(rng));
        p.emplace_back(radius * std::cos(angle), radius * std::sin(angle), 0.5 * unit(rng));
        angle += 3.0 * std::numbers::pi / m * (0.3 + std::abs(unit(rng)));
      }
    }
    const auto x = positions(p);
    const VertexFans fans(tris, m + 1);
    const bool by_axis = certified_two_signs_per_sector(fans, x, 0);
    const bool now = fans.certified(x, 0);
    if (by_axis) {
      ASSERT_TRUE(now) << "case " << n;
    }
    if (now && !by_axis) {
      ++by_normal;
      ASSERT_FALSE(some_pair_intersects(tris, x)) << "case " << n;
    }
    ++(now ? certified : refused);
  }
  EXPECT_GT(certified, 2000);
  EXPECT_GT(refused, 2000);
  EXPECT_GT(by_normal, 20);
  std::int64_t axis_total = 0, now_total = 0;
  for (const std::string file : {"CesiumMan.glb", "RobotExpressive.glb"}) {
    const auto model = skinning::load_model(test::asset("characters/" + file));
    const skinning::Topology topo = skinning::build_topology(*model.mesh);
    const FeatureTopology ft(*model.mesh, topo);
    const VertexFans& fans = ft.fans();
    const auto motion = model.motion();
    skinning::Positions posed, welded;
    for (const int k : {0, motion->num_samples() / 2}) {
      motion->positions(k, posed);
      skinning::gather_welded(topo, posed, welded);
      for (std::int32_t v = 0; v < topo.num_welded_vertices(); ++v) {
        const bool by_axis = certified_two_signs_per_sector(fans, welded, v);
        const bool now = fans.certified(welded, v);
        if (by_axis) {
          ASSERT_TRUE(now) << file << " sample " << k << " vertex " << v;
        }
        if (now && !by_axis) {
          ASSERT_FALSE(some_pair_intersects(fan_of(fans, v), welded))
              << file << " sample " << k << " vertex " << v;
        }
        axis_total += by_axis ? 1 : 0;
        now_total += now ? 1 : 0;
      }
    }
  }
  // RobotExpressive's hard-edged parts: the normal certifies hundreds more (1,503 → 1,796 of
  // 1,820 vertices at its first sample).
  EXPECT_GT(now_total, axis_total + 200);
}

// Fans that no coordinate projection sees injectively, certified along their own normal: a
// cube's corner (three faces, each on a coordinate plane: dropping any axis flattens one of them)
// and the tip of a narrow cone pointing along a diagonal. Each has no intersecting pair.
TEST(VertexFans, FansThatNoAxisSeesAreCertifiedAlongTheirNormal) {
  const auto corner_tris = fan(3, true);
  const VertexFans corner(corner_tris, 4);
  const auto xc = positions({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}});
  EXPECT_TRUE(corner.certified(xc, 0));
  EXPECT_FALSE(some_pair_intersects(corner_tris, xc));
  EXPECT_FALSE(certified_two_signs_per_sector(corner, xc, 0)) << "no axis sees it";
  // Cone tip: 7 spokes on a circle of radius 0.2 at height 1 along (1, 1, 1) (an odd number: no
  // two spokes opposite, which the projection along the axis would see on one line).
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 1).normalized();
  const Eigen::Vector3d u = axis.cross(Eigen::Vector3d(1, 0, 0)).normalized();
  const Eigen::Vector3d w = axis.cross(u);
  std::vector<Eigen::Vector3d> p{Eigen::Vector3d::Zero()};
  for (int i = 0; i < 7; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 7.0;
    p.push_back(axis + 0.2 * (std::cos(a) * u + std::sin(a) * w));
  }
  const auto cone_tris = fan(7, true);
  const VertexFans cone(cone_tris, 8);
  const auto xt = positions(p);
  EXPECT_TRUE(cone.certified(xt, 0));
  EXPECT_FALSE(some_pair_intersects(cone_tris, xt));
  EXPECT_FALSE(certified_two_signs_per_sector(cone, xt, 0)) << "no axis sees it";
  // The same cone turned inside out halfway (two spokes swapped): the fan folds over itself and
  // stays refused whatever the projection.
  std::swap(p[3], p[4]);
  const auto xf = positions(p);
  EXPECT_FALSE(cone.certified(xf, 0));
}

// certify() first tries, for each closed fan, the projection its predecessor in vertex order
// chose, then certified()'s own: it accepts every fan certified() accepts, and each fan it accepts
// beyond those has no intersecting pair by the exact test. On a soup of random closed fans — flat
// ones that wind twice (intersecting, refused by every projection), bumpy and tilted ones — where
// the predecessor's projection is often not the fan's own, and on real characters.
TEST(VertexFans, CertifyTriesThePredecessorsProjectionAndStaysSound) {
  std::mt19937_64 rng(4321);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> spokes(3, 9);
  std::vector<Tri> tris;
  std::vector<Eigen::Vector3d> p;
  for (int n = 0; n < 4000; ++n) {
    const int m = spokes(rng);
    const auto centre = static_cast<std::int32_t>(p.size());
    for (const Tri& t : fan(m, true)) tris.push_back({centre + t[0], centre + t[1], centre + t[2]});
    const double spread = (n % 4 == 0) ? 4.0 : 2.0;  // a quarter wind about twice
    const double bump = (n % 3 == 0) ? 0.0 : std::abs(unit(rng)) * 1.5;
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(
            unit(rng) * 3.0, Eigen::Vector3d(unit(rng), unit(rng), unit(rng) + 2).normalized())
            .toRotationMatrix();
    const Eigen::Vector3d at(3.0 * n, 0.0, 0.0);  // apart: each fan is its own component
    p.push_back(at);
    double angle = 0;
    for (int i = 0; i < m; ++i) {
      const double radius = 0.2 + std::abs(unit(rng));
      p.push_back(
          at + r * Eigen::Vector3d(
                       radius * std::cos(angle), radius * std::sin(angle), bump * unit(rng)));
      angle += spread * std::numbers::pi / m * (0.3 + std::abs(unit(rng)));
    }
  }
  const auto x = positions(p);
  const VertexFans fans(tris, static_cast<std::int32_t>(p.size()));
  std::vector<std::uint8_t> batch;
  fans.certify(x, batch);
  int alone = 0, beyond = 0, refused_intersecting = 0;
  for (std::int32_t v = 0; v < static_cast<std::int32_t>(p.size()); ++v) {
    if (!fans.closed(v)) continue;  // a spoke's own fan (two triangles, open)
    const bool single = fans.certified(x, v);
    const bool many = batch[static_cast<std::size_t>(v)] != 0;
    if (single) {
      ASSERT_TRUE(many) << "fan " << v;
      ++alone;
    }
    if (many && !single) {
      ++beyond;
      ASSERT_FALSE(some_pair_intersects(fan_of(fans, v), x)) << "fan " << v;
    }
    if (!many && some_pair_intersects(fan_of(fans, v), x)) ++refused_intersecting;
  }
  EXPECT_GT(alone, 2000);
  EXPECT_GT(beyond, 20);
  EXPECT_GT(refused_intersecting, 400);
  // Real characters: the same two properties at two samples.
  std::int64_t extra = 0;
  for (const std::string file :
       {"CesiumMan.glb", "RobotExpressive.glb", "stormtrooper/stormtrooper.dae"}) {
    const test::WeldedCharacter character(file);
    const FeatureTopology ft(*character.loaded.mesh, character.topology);
    for (const int k : {0, character.loaded.motion()->num_samples() / 2}) {
      const skinning::Positions welded = character.sample(k);
      ft.fans().certify(welded, batch);
      for (std::int32_t v = 0; v < character.topology.num_welded_vertices(); ++v) {
        const bool single = ft.fans().certified(welded, v);
        const bool many = batch[static_cast<std::size_t>(v)] != 0;
        if (single) {
          ASSERT_TRUE(many) << file << " sample " << k << " vertex " << v;
        }
        if (many && !single) {
          ++extra;
          ASSERT_FALSE(some_pair_intersects(fan_of(ft.fans(), v), welded))
              << file << " sample " << k << " vertex " << v;
        }
      }
    }
  }
  EXPECT_GT(extra, 20);
}

/// The exact triangle test under another name: run_dcd_tests settles pairs by fans only for
/// ccd::triangles_intersect itself, so this one sees every pair (the reference).
bool every_pair(const ccd::TriangleTriangleQuery& q, const ccd::SharedCorners& shared) {
  return ccd::triangles_intersect(q, shared);
}

// On real characters, at rest and at posed samples: the same pairs with and without fans, and the
// fans settle most of the pairs that share a corner.
TEST(VertexFans, DcdOnRealCharactersIsUnchangedAndTestsFewerPairs) {
  for (const std::string file :
       {"CesiumMan.glb", "RobotExpressive.glb", "stormtrooper/stormtrooper.dae"}) {
    const auto model = skinning::load_model(test::asset("characters/" + file));
    const skinning::Mesh& mesh = *model.mesh;
    const skinning::Topology topo = skinning::build_topology(mesh);
    const auto motion = model.motion();
    auto with_fans = make_method("bvh", mesh, topo);
    auto without = make_method("bvh", mesh, topo, {.elementary = {.triangles = &every_pair}});
    skinning::Positions posed, welded;
    std::int64_t tests_with = 0, tests_without = 0, pairs = 0;
    const int n = motion->num_samples();
    for (const int k : {-1, 0, n / 2, n - 1}) {
      if (k < 0) {
        skinning::gather_welded(topo, mesh.rest_positions, welded);
      } else {
        motion->positions(k, posed);
        skinning::gather_welded(topo, posed, welded);
      }
      FrameResult a, b;
      with_fans->detect_dcd(welded, a);
      without->detect_dcd(welded, b);
      ASSERT_EQ(a.dcd_pairs, b.dcd_pairs) << file << " sample " << k;
      EXPECT_EQ(a.counters.candidate_pairs, b.counters.candidate_pairs);
      tests_with += a.counters.tt_tests;
      tests_without += b.counters.tt_tests;
      pairs += static_cast<std::int64_t>(a.dcd_pairs.size());
    }
    EXPECT_GT(pairs, 0) << file;
    EXPECT_LT(tests_with * 2, tests_without) << file << ": fans settle most pairs";
  }
}

/// The product's CCD kernels under other names (renamed_kernels.hpp): the culling stages settle
/// pairs by fans only for ccd::vertex_face_ccd / ccd::edge_edge_ccd themselves, so these see
/// every feature pair.
constexpr auto every_vf = &test::renamed_vertex_face_ccd;
constexpr auto every_ee = &test::renamed_edge_edge_ccd;

/// The triangles as a mesh's index rows.
skinning::Triangles as_triangles(const std::vector<Tri>& tris) {
  skinning::Triangles f(static_cast<Eigen::Index>(tris.size()), 3);
  for (std::size_t i = 0; i < tris.size(); ++i) {
    f.row(static_cast<Eigen::Index>(i)) << tris[i][0], tris[i][1], tris[i][2];
  }
  return f;
}

/// The positions at t of the straight-line motion x0 → x1.
skinning::Positions lerp(const skinning::Positions& x0, const skinning::Positions& x1, double t) {
  return (1.0 - t) * x0 + t * x1;
}

/// The exact CCD contacts of a mesh over x0 → x1 with every feature pair tested (brute force).
std::vector<CcdContact> every_contact(
    const skinning::Mesh& mesh,
    const skinning::Topology& topo,
    const skinning::Positions& x0,
    const skinning::Positions& x1) {
  auto brute = make_method(
      "brute",
      mesh,
      topo,
      {.accuracy = ccd::Accuracy::exact,
       .elementary = {.vertex_face = every_vf, .edge_edge = every_ee}});
  FrameResult r;
  brute->detect_ccd(x0, x1, r);
  return r.contacts;
}

TEST(VertexFans, CertifiedOverAnIntervalOnlyWhileEverySectorKeepsItsOrientation) {
  const auto tris = fan(5, true);
  const VertexFans fans(tris, 6);
  const double step = 2.0 * std::numbers::pi / 5.0;
  const auto x0 =
      positions(star({0, step, 2 * step, 3 * step, 4 * step}, {0.3, -0.3, 0.3, -0.3, 0}));
  // Turned by 20° and moved: certified throughout.
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  skinning::Positions x1 = x0;
  for (Eigen::Index i = 0; i < x1.rows(); ++i) {
    x1.row(i) =
        (r * Eigen::Vector3d(x0.row(i).transpose())).transpose() + Eigen::RowVector3d(2, 1, 0);
  }
  EXPECT_TRUE(fans.certified_over(x0, x1, 0));
  // Turned by a half-turn about v on straight lines: certified at both ends, yet every spoke
  // passes through v at t = 1/2 — refused.
  const skinning::Positions half = -x0;
  EXPECT_TRUE(fans.certified(x0, 0));
  EXPECT_TRUE(fans.certified(half, 0));
  EXPECT_FALSE(fans.certified_over(x0, half, 0));
  // An umbrella turned inside out (v from above the ring to below it): the fan passes through
  // flat but never meets itself — certified, and no pair meets at any instant sampled.
  const auto up =
      positions(star({0, step, 2 * step, 3 * step, 4 * step}, {-0.5, -0.5, -0.5, -0.5, -0.5}));
  const auto down =
      positions(star({0, step, 2 * step, 3 * step, 4 * step}, {0.5, 0.5, 0.5, 0.5, 0.5}));
  EXPECT_TRUE(fans.certified_over(up, down, 0));
  for (int k = 0; k <= 10; ++k) EXPECT_FALSE(some_pair_intersects(tris, lerp(up, down, k / 10.0)));
  // Open fans are never certified over an interval.
  const auto open_tris = fan(5, false);
  const auto xo = positions(star({0, 0.5, 1.0, 1.5, 2.0}, {0, 0, 0, 0, 0}));
  EXPECT_TRUE(VertexFans(open_tris, 6).certified(xo, 0));
  EXPECT_FALSE(VertexFans(open_tris, 6).certified_over(xo, xo, 0));
}

// Random closed fans on random straight-line motions, from gentle to wild: a fan certified over
// the interval has no intersecting pair at any sampled instant and no contact by the exact CCD of
// every feature pair; both outcomes occur often, and refused fans with contacts do too.
TEST(VertexFans, FansCertifiedOverAnIntervalHaveNoContacts) {
  std::mt19937_64 rng(4321);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> spokes(3, 9);
  int certified = 0, refused = 0, refused_with_contacts = 0;
  for (int n = 0; n < 400; ++n) {
    const int m = spokes(rng);
    const auto tris = fan(m, true);
    const skinning::Triangles f = as_triangles(tris);
    std::vector<Eigen::Vector3d> p{Eigen::Vector3d::Zero()};
    double angle = 0;
    for (int i = 0; i < m; ++i) {
      const double radius = 0.3 + std::abs(unit(rng));
      p.emplace_back(radius * std::cos(angle), radius * std::sin(angle), 0.4 * unit(rng));
      angle += 2.0 * std::numbers::pi / m * (0.7 + 0.3 * std::abs(unit(rng)));
    }
    const auto x0 = positions(p);
    // Each point moves by up to `reach`: small motions keep the fan, large ones fold it.
    const double reach = (n % 4 + 1) * 0.35;
    skinning::Positions x1 = x0;
    for (Eigen::Index i = 0; i < x1.rows(); ++i) {
      x1.row(i) += reach * Eigen::RowVector3d(unit(rng), unit(rng), unit(rng));
    }
    const VertexFans fans(tris, m + 1);
    const auto mesh = test::single_part_mesh(x0, f);
    const auto topo = test::simple_topology(mesh);
    const auto contacts = every_contact(mesh, topo, x0, x1);
    if (fans.certified_over(x0, x1, 0)) {
      ++certified;
      ASSERT_TRUE(contacts.empty()) << "case " << n;
      for (int k = 0; k <= 8; ++k) {
        ASSERT_FALSE(some_pair_intersects(tris, lerp(x0, x1, k / 8.0))) << "case " << n;
      }
    } else {
      ++refused;
      refused_with_contacts += contacts.empty() ? 0 : 1;
    }
  }
  EXPECT_GT(certified, 60);
  EXPECT_GT(refused, 60);
  EXPECT_GT(refused_with_contacts, 20);
}

// The half-turn fan through its vertex has contacts at t = 1/2 although its fan is certified at
// both ends: every method still reports each of them (a rule that looked at the ends only would
// drop them all).
TEST(VertexFans, FanTurnedThroughItsVertexKeepsItsContacts) {
  const auto tris = fan(6, true);
  const skinning::Triangles f = as_triangles(tris);
  const double step = std::numbers::pi / 3.0;
  const auto x0 = positions(
      star({0, step, 2 * step, 3 * step, 4 * step, 5 * step}, {0.2, -0.2, 0.2, -0.2, 0.2, -0.2}));
  const skinning::Positions x1 = -x0;
  const auto mesh = test::single_part_mesh(x0, f);
  const auto topo = test::simple_topology(mesh);
  const auto reference = every_contact(mesh, topo, x0, x1);
  ASSERT_FALSE(reference.empty());
  for (const std::string name : {"brute", "bvh", "kdop", "enhanced-dual-cone", "auto"}) {
    auto method = make_method(name, mesh, topo, {.accuracy = ccd::Accuracy::exact});
    FrameResult r;
    method->detect_ccd(x0, x1, r);
    EXPECT_EQ(r.contacts, reference) << name;
  }
}

// On real characters over their clips: the same contacts with and without the fans over each
// interval, and fewer elementary tests with them.
TEST(VertexFans, CcdOnRealCharactersIsUnchangedAndTestsFewerPairs) {
  // `bvh` and `kdop` settle the pairs that share a vertex certified over the interval in their
  // traversal (FanSieve); the substituted tests turn the fans off (ccd_uses_fans), so `without`
  // sees every pair. `kdop`'s relative-box trial then judges other pairs, so only `bvh`'s
  // candidate count must be the same.
  for (const std::string method : {"bvh", "kdop"}) {
    for (const std::string file : {"CesiumMan.glb", "stormtrooper/stormtrooper.dae"}) {
      const test::WeldedCharacter character(file);
      const skinning::Mesh& mesh = *character.loaded.mesh;
      auto with_fans = make_method(method, mesh, character.topology);
      // The same in blocks of 64 pairs: the sieve's counts do not depend on where blocks end.
      auto small_blocks = make_method(method, mesh, character.topology, {.block_pairs = 64});
      auto without = make_method(
          method,
          mesh,
          character.topology,
          {.elementary = {.vertex_face = every_vf, .edge_edge = every_ee}});
      std::int64_t tests_with = 0, tests_without = 0, contacts = 0;
      const int n = character.loaded.motion()->num_samples();
      for (int k = 0; k + 1 < n; k += std::max(1, n / 12)) {
        const skinning::Positions x0 = character.sample(k);
        const skinning::Positions x1 = character.sample(k + 1);
        FrameResult a, b, c;
        with_fans->detect_ccd(x0, x1, a);
        without->detect_ccd(x0, x1, b);
        small_blocks->detect_ccd(x0, x1, c);
        ASSERT_EQ(a.contacts, b.contacts) << method << " " << file << " interval " << k;
        if (method == "bvh") {
          EXPECT_EQ(a.counters.candidate_pairs, b.counters.candidate_pairs) << file << " " << k;
        }
        ASSERT_EQ(c.contacts, a.contacts) << method << " " << file << " interval " << k;
        EXPECT_EQ(c.counters.candidate_pairs, a.counters.candidate_pairs) << method << " " << k;
        EXPECT_EQ(c.counters.vf_tests, a.counters.vf_tests) << method << " " << k;
        EXPECT_EQ(c.counters.ee_tests, a.counters.ee_tests) << method << " " << k;
        tests_with += a.counters.vf_tests + a.counters.ee_tests;
        tests_without += b.counters.vf_tests + b.counters.ee_tests;
        contacts += static_cast<std::int64_t>(a.contacts.size());
      }
      EXPECT_GT(contacts, 0) << method << " " << file;
      EXPECT_LT(tests_with, tests_without) << method << " " << file;
    }
  }
}

}  // namespace
}  // namespace skelcd::culling
