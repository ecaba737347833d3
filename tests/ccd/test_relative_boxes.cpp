// The relative-box stage of the conservative kernels (CcdOptions::relative_boxes,
// ccd/detail/relative_boxes.hpp; docs/ccd.md "Relative boxes"): it only turns answers from hit to
// no hit, only where the exact kernel finds no contact, and never on the ground-truthed
// cloth-funnel contacts; features that move together close to coplanar — which the coplanarity
// stage cannot reject — are rejected by it; contact distance widens the boxes.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <string>

#include "ccd/detail/relative_boxes.hpp"
#include "ccd/edge_edge.hpp"
#include "ccd/exact_ccd.hpp"
#include "ccd/vertex_face.hpp"
#include "tests/ccd/cloth_funnel.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

CcdOptions with_relative(bool on, double min_separation = 0.0) {
  CcdOptions o;
  o.min_separation = min_separation;
  o.relative_boxes = on;
  return o;
}

// Random and near-degenerate queries (contacts built on purpose, grids, common planes, scaled
// 10^-6 … 10^6): with the stage, a hit is a hit without it, and a hit it removes is no contact
// for the exact kernel.
TEST(RelativeBoxes, OnlyRemovesHitsThatAreNoContact) {
  test::RandomQueryGenerator gen(2611);
  int removed_hits = 0;
  int hits = 0;
  CcdStats stats;
  for (int i = 0; i < 40'000; ++i) {
    const test::RandomQuery q = gen.next();
    CcdStats off_stats;
    const CcdResult off =
        q.vertex_face
            ? vertex_face_ccd(q.vf(), Accuracy::conservative, with_relative(false), off_stats)
            : edge_edge_ccd(q.ee(), Accuracy::conservative, with_relative(false), off_stats);
    const CcdResult on =
        q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, with_relative(true), stats)
                      : edge_edge_ccd(q.ee(), Accuracy::conservative, with_relative(true), stats);
    hits += off.hit ? 1 : 0;
    if (on.hit) {
      ASSERT_TRUE(off.hit) << q.kind << " query " << i;
      EXPECT_EQ(on.toi_lower, off.toi_lower) << q.kind << " query " << i;
      continue;
    }
    if (!off.hit) continue;
    ++removed_hits;
    const bool exact = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::exact).hit
                                     : edge_edge_ccd(q.ee(), Accuracy::exact).hit;
    EXPECT_FALSE(exact) << q.kind << " query " << i << ": a contact removed";
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(stats.relative_rejected, 0);
  // Every query the stage rejected left the coplanarity stage undecided: the counters add up.
  EXPECT_EQ(
      stats.aabb_rejected + stats.coplanarity_rejected + stats.relative_rejected +
          stats.algebraic_rejected + stats.algebraic_hits + stats.solver_runs,
      stats.queries);
  std::cout << "  relative boxes: " << stats.relative_rejected << " of " << stats.queries
            << " rejected, " << removed_hits << " conservative false positives removed\n";
}

// The published cloth-funnel step: every contact of its ground truth stays a hit.
TEST(RelativeBoxes, KeepsEveryClothFunnelContact) {
  for (const std::string kind : {"vf", "ee"}) {
    const auto queries = test::load_cloth_funnel(kind);
    int contacts = 0;
    for (std::size_t i = 0; i < queries.size(); ++i) {
      const auto& q = queries[i];
      const CcdResult r = q.vertex_face
                              ? vertex_face_ccd(q.vf(), Accuracy::conservative, with_relative(true))
                              : edge_edge_ccd(q.ee(), Accuracy::conservative, with_relative(true));
      if (!q.truth) continue;
      ++contacts;
      EXPECT_TRUE(r.hit) << kind << " query " << i;
    }
    EXPECT_EQ(contacts, kind == "vf" ? 27 : 107);
  }
}

// Two parallel edges in one plane, 1 apart, carried together by 10 in that plane: the coplanarity
// cubic is 0 throughout (nothing for that stage to reject) and their swept boxes overlap; their
// relative boxes are 1 apart. With contact distance 0.9 they are still rejected; with 1.1 (and the
// same motion) they are within reach all along and stay a hit.
TEST(RelativeBoxes, RejectsCoplanarFeaturesThatMoveTogether) {
  const Eigen::Vector3d carry(10.0, 3.0, 0.0);
  EdgeEdgeQuery q;
  q.ea0_t0 = {0.0, 0.0, 0.0};
  q.ea1_t0 = {2.0, 0.0, 0.0};
  q.eb0_t0 = {0.0, 1.0, 0.0};
  q.eb1_t0 = {2.0, 1.0, 0.0};
  q.ea0_t1 = q.ea0_t0 + carry;
  q.ea1_t1 = q.ea1_t0 + carry;
  q.eb0_t1 = q.eb0_t0 + carry;
  q.eb1_t1 = q.eb1_t0 + carry;
  CcdStats on, off;
  EXPECT_FALSE(edge_edge_ccd(q, Accuracy::conservative, with_relative(true), on).hit);
  EXPECT_EQ(on.relative_rejected, 1);
  EXPECT_FALSE(edge_edge_ccd(q, Accuracy::conservative, with_relative(false), off).hit);
  EXPECT_EQ(off.relative_rejected, 0);
  EXPECT_EQ(off.coplanarity_rejected, 0) << "the coplanarity stage cannot decide it";
  CcdStats near;
  EXPECT_FALSE(edge_edge_ccd(q, Accuracy::conservative, with_relative(true, 0.9), near).hit);
  EXPECT_EQ(near.relative_rejected, 1);
  CcdStats within;
  EXPECT_TRUE(edge_edge_ccd(q, Accuracy::conservative, with_relative(true, 1.1), within).hit);
  EXPECT_EQ(within.relative_rejected, 0);
  // The vertex-face form: a vertex in the face's plane, 1 beside the face, carried along.
  VertexFaceQuery v;
  v.v_t0 = {-1.0, 0.5, 0.0};
  v.f0_t0 = {0.0, 0.0, 0.0};
  v.f1_t0 = {2.0, 0.0, 0.0};
  v.f2_t0 = {0.0, 2.0, 0.0};
  v.v_t1 = v.v_t0 + carry;
  v.f0_t1 = v.f0_t0 + carry;
  v.f1_t1 = v.f1_t0 + carry;
  v.f2_t1 = v.f2_t0 + carry;
  CcdStats vf;
  EXPECT_FALSE(vertex_face_ccd(v, Accuracy::conservative, with_relative(true), vf).hit);
  EXPECT_EQ(vf.relative_rejected, 1);
  CcdStats vf_within;
  EXPECT_TRUE(vertex_face_ccd(v, Accuracy::conservative, with_relative(true, 1.1), vf_within).hit);
}

// Four points at t = 0 and t = 1 whose every coordinate lies in [1, 2) on a grid of a few ulps,
// each moved by about 0.1 in the last bits: ends and projections tie and cross at the last bit,
// and a difference or sum of two coordinates is exact in long double (at most 57 significant
// bits).
struct GridQuery {
  std::mt19937 rng;
  std::uniform_int_distribution<int> grid{-6, 6};
  std::uniform_int_distribution<int> low_bits{0, 64};
  std::array<Eigen::Vector3d, 4> p0, p1;
  std::array<const Eigen::Vector3d*, 4> t0{&p0[0], &p0[1], &p0[2], &p0[3]};
  std::array<const Eigen::Vector3d*, 4> t1{&p1[0], &p1[1], &p1[2], &p1[3]};

  explicit GridQuery(std::uint32_t seed) : rng(seed) {}
  GridQuery(const GridQuery&) = delete;
  GridQuery& operator=(const GridQuery&) = delete;
  void next() {
    constexpr double kUlp = 0x1p-52;
    for (std::size_t i = 0; i < 4; ++i) {
      for (Eigen::Index k = 0; k < 3; ++k) {
        p0[i][k] = 1.5 + grid(rng) * kUlp;
        p1[i][k] = p0[i][k] + (0.1 + low_bits(rng) * 0x1p-56);
      }
    }
  }
};

// relative_boxes_apart without contact distance (which the pipeline no longer asks: its stage is
// then ends_apart) compares rounded ends fl(p₁ − u) unbracketed (relative_boxes.hpp). On the grid,
// with u formed as the function forms it, p₁ − u is exact in long double. Every query it calls
// apart, for a vertex and a face (NA = 1) and for two edges (NA = 2), must have exactly separated
// relative boxes.
template <std::size_t NA>
void expect_apart_only_when_exactly_apart(std::uint32_t seed) {
  static_assert(std::numeric_limits<long double>::digits >= 64);
  GridQuery q(seed);
  int apart = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    q.next();
    if (!detail::relative_boxes_apart<NA>(q.t0, q.t1, 0.0)) continue;
    ++apart;
    const auto& p0 = q.p0;
    const auto& p1 = q.p1;
    const Eigen::Vector3d u =
        0.25 * (((p1[0] - p0[0]) + (p1[1] - p0[1])) + ((p1[2] - p0[2]) + (p1[3] - p0[3])));
    bool exactly_apart = false;
    for (Eigen::Index k = 0; k < 3; ++k) {
      std::array<long double, 2> lo{INFINITY, INFINITY}, hi{-INFINITY, -INFINITY};
      for (std::size_t i = 0; i < 4; ++i) {
        const std::size_t side = i < NA ? 0 : 1;
        const long double end = static_cast<long double>(p1[i][k]) - static_cast<long double>(u[k]);
        lo[side] = std::min({lo[side], static_cast<long double>(p0[i][k]), end});
        hi[side] = std::max({hi[side], static_cast<long double>(p0[i][k]), end});
      }
      exactly_apart = exactly_apart || hi[0] < lo[1] || hi[1] < lo[0];
    }
    ASSERT_TRUE(exactly_apart) << "trial " << trial;
  }
  EXPECT_GT(apart, 1000);  // enough separated queries for the check to mean something
}

TEST(RelativeBoxes, WithoutContactDistanceApartOnlyWhenTheExactBoxesAre) {
  expect_apart_only_when_exactly_apart<1>(20261127);
  expect_apart_only_when_exactly_apart<2>(20261128);
}

// Without contact distance the stage is ends_apart (relative_boxes.hpp): nine directions, each
// projection a coordinate or one rounded sum or difference of two, compared unbracketed. On the
// same grid of a few ulps a sum or difference of two coordinates is exact in long double, so each
// query the stage calls apart must be apart, exactly, on one direction at t = 0 and at t = 1, the
// same way round.
template <std::size_t NA>
void expect_ends_apart_only_when_exactly_apart(std::uint32_t seed) {
  static_assert(std::numeric_limits<long double>::digits >= 64);
  GridQuery q(seed);
  const auto& p0 = q.p0;
  const auto& p1 = q.p1;
  const auto project = [](const Eigen::Vector3d& p, int d) {
    const long double x = p[0], y = p[1], z = p[2];
    const long double v[9] = {x, y, z, x + y, y + z, z + x, x - y, y - z, z - x};
    return v[d];
  };
  int apart = 0;
  for (int trial = 0; trial < 200000; ++trial) {
    q.next();
    if (!detail::ends_apart<NA>(q.t0, q.t1)) continue;
    ++apart;
    bool exactly_apart = false;
    for (int d = 0; d < 9; ++d) {
      // lo/hi[time][side]
      long double lo[2][2] = {{INFINITY, INFINITY}, {INFINITY, INFINITY}};
      long double hi[2][2] = {{-INFINITY, -INFINITY}, {-INFINITY, -INFINITY}};
      for (std::size_t time = 0; time < 2; ++time) {
        for (std::size_t i = 0; i < 4; ++i) {
          const std::size_t side = i < NA ? 0 : 1;
          const long double v = project(time == 0 ? p0[i] : p1[i], d);
          lo[time][side] = std::min(lo[time][side], v);
          hi[time][side] = std::max(hi[time][side], v);
        }
      }
      exactly_apart = exactly_apart || (hi[0][0] < lo[0][1] && hi[1][0] < lo[1][1]) ||
                      (hi[0][1] < lo[0][0] && hi[1][1] < lo[1][0]);
    }
    ASSERT_TRUE(exactly_apart) << "trial " << trial;
  }
  EXPECT_GT(apart, 1000);  // enough separated queries for the check to mean something
}

TEST(RelativeBoxes, EndsApartOnlyWhenTheExactProjectionsAre) {
  expect_ends_apart_only_when_exactly_apart<1>(20261130);
  expect_ends_apart_only_when_exactly_apart<2>(20261131);
}

// Two edges in z = 0 that only the diagonal x + y separates (their boxes overlap), still over the
// interval: apart; the same with the second edge carried across the first: apart at t = 0 only,
// so not apart. A non-finite coordinate: never apart.
TEST(RelativeBoxes, EndsApartOnADiagonalAndNotWhenCrossing) {
  std::array<Eigen::Vector3d, 4> p0{
      Eigen::Vector3d(-2.0, 1.0, 0.0),
      Eigen::Vector3d(1.0, -2.0, 0.0),
      Eigen::Vector3d(2.0, -1.0, 0.0),
      Eigen::Vector3d(-1.0, 2.0, 0.0)};
  std::array<Eigen::Vector3d, 4> p1 = p0;
  const std::array<const Eigen::Vector3d*, 4> t0{&p0[0], &p0[1], &p0[2], &p0[3]};
  const std::array<const Eigen::Vector3d*, 4> t1{&p1[0], &p1[1], &p1[2], &p1[3]};
  EXPECT_TRUE(detail::ends_apart<2>(t0, t1));
  p1[2] -= Eigen::Vector3d(4.0, 4.0, 0.0);
  p1[3] -= Eigen::Vector3d(4.0, 4.0, 0.0);
  EXPECT_FALSE(detail::ends_apart<2>(t0, t1));
  p1 = p0;
  p1[0][2] = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(detail::ends_apart<2>(t0, t1));
}

}  // namespace
}  // namespace skelcd::ccd
