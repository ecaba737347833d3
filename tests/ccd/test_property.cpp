// Seeded property test: conservative never misses a contact the exact reference finds, on a mix
// of random and near-degenerate queries (tests/ccd/random_queries.hpp). The long run (>= 10^6
// queries) is bench/ccd/bm_ccd_property.

#include <iostream>
#include <random>
#include <map>

#include <gtest/gtest.h>

#include "ccd/exact_ccd.hpp"
#include "ccd/filters.hpp"
#include "tests/ccd/random_queries.hpp"

namespace skelcd::ccd {
namespace {

constexpr int kQueries = 4000;

TEST(ConservativeProperty, NeverMissesWhatTheExactReferenceFinds) {
  test::RandomQueryGenerator gen(20240601);
  std::map<std::string_view, std::array<int, 3>> per_kind;  // queries, exact hits, false positives
  int false_negatives = 0;
  for (int i = 0; i < kQueries; ++i) {
    const auto q = gen.next();
    const ExactCcdResult e = q.vertex_face ? vertex_face_ccd_rational(to_rational(q.vf()))
                                           : edge_edge_ccd_rational(to_rational(q.ee()));
    const CcdResult c = q.vertex_face ? vertex_face_ccd(q.vf()) : edge_edge_ccd(q.ee());
    auto& k = per_kind[q.kind];
    ++k[0];
    if (e.hit) ++k[1];
    if (!e.hit && c.hit) ++k[2];
    if (e.hit && !c.hit) {
      ++false_negatives;
      ADD_FAILURE() << "false negative #" << i << " (" << q.kind << ")";
    }
    if (e.hit && c.hit) {
      EXPECT_LE(mpq_class(c.toi_lower), e.toi_hi) << "query #" << i;
    }
  }
  EXPECT_EQ(false_negatives, 0);
  for (const auto& [kind, k] : per_kind) {
    std::cout << "  " << kind << ": " << k[0] << " queries, " << k[1] << " exact hits, " << k[2]
              << " false positives\n";
    EXPECT_GT(k[1], 0) << kind << " never produced a contact: the mix is not testing anything";
  }
}

TEST(ConservativeProperty, FiltersNeverRejectAContact) {
  test::RandomQueryGenerator gen(77);
  int contacts = 0;
  for (int i = 0; i < kQueries; ++i) {
    const auto q = gen.next();
    const bool hit = q.vertex_face ? vertex_face_ccd_rational(to_rational(q.vf())).hit
                                   : edge_edge_ccd_rational(to_rational(q.ee())).hit;
    if (!hit) continue;
    ++contacts;
    if (q.vertex_face) {
      EXPECT_FALSE(swept_aabbs_disjoint(q.vf())) << i;
      EXPECT_FALSE(coplanarity_filter_rejects(q.vf())) << i;
      EXPECT_FALSE(coplanarity_filter_rejects(q.vf(), 1e-3)) << i;
    } else {
      EXPECT_FALSE(swept_aabbs_disjoint(q.ee())) << i;
      EXPECT_FALSE(coplanarity_filter_rejects(q.ee())) << i;
      EXPECT_FALSE(coplanarity_filter_rejects(q.ee(), 1e-3)) << i;
    }
  }
  EXPECT_GT(contacts, kQueries / 10);
}

TEST(ConservativeProperty, ContactStaysAHitForAnyMinSeparation) {
  test::RandomQueryGenerator gen(99);
  int contacts = 0;
  for (int i = 0; i < kQueries / 2; ++i) {
    const auto q = gen.next();
    const bool hit = q.vertex_face ? vertex_face_ccd_rational(to_rational(q.vf())).hit
                                   : edge_edge_ccd_rational(to_rational(q.ee())).hit;
    if (!hit) continue;
    ++contacts;
    CcdOptions options;
    options.min_separation = std::ldexp(1.0, -(i % 40));
    const auto c = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, options)
                                 : edge_edge_ccd(q.ee(), Accuracy::conservative, options);
    EXPECT_TRUE(c.hit) << i;
  }
  EXPECT_GT(contacts, 100);
}

TEST(ConservativeProperty, PerturbedContactsAreHitsWithinTheirPerturbation) {
  // Moving every coordinate of a touching query by at most delta moves every point of both
  // primitives by at most sqrt(3) delta at every time, so the perturbed query comes within
  // 2 sqrt(3) delta <= 4 delta of contact: with min_separation 4 delta it must be a hit. (This is
  // what `skelcd ccd-queries` relies on for numbers that are not exactly doubles.)
  test::RandomQueryGenerator gen(123);
  std::mt19937_64 rng(5);
  int contacts = 0;
  for (int i = 0; i < kQueries / 2; ++i) {
    auto q = gen.next();
    const bool hit = q.vertex_face ? vertex_face_ccd_rational(to_rational(q.vf())).hit
                                   : edge_edge_ccd_rational(to_rational(q.ee())).hit;
    if (!hit) continue;
    ++contacts;
    double scale = 0.0;
    for (const auto& p : q.points) scale = std::max(scale, p.cwiseAbs().maxCoeff());
    const double delta = std::ldexp(std::max(scale, 1e-300), -std::uniform_int_distribution<int>(20, 52)(rng));
    std::uniform_real_distribution<double> r(-1.0, 1.0);
    double moved = 0.0;
    for (auto& p : q.points) {
      for (int k = 0; k < 3; ++k) {
        const double before = p[k];
        p[k] += r(rng) * delta;
        moved = std::max(moved, std::abs(p[k] - before));
      }
    }
    CcdOptions options;
    options.min_separation = 4 * moved * (1 + 1e-12);
    const auto c = q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, options)
                                 : edge_edge_ccd(q.ee(), Accuracy::conservative, options);
    EXPECT_TRUE(c.hit) << "query " << i << " (" << q.kind << "), delta " << delta;
  }
  EXPECT_GT(contacts, 300);
}

}  // namespace
}  // namespace skelcd::ccd
