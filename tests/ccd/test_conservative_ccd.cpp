// The conservative accuracy on the hard-case families: zero false negatives against the exact
// reference, a sound time of impact, its false-positive rate stated; and `fast` shown to miss.

#include <iomanip>
#include <iostream>
#include <map>

#include <gtest/gtest.h>

#include "ccd/exact_ccd.hpp"
#include "tests/ccd/hard_cases.hpp"

namespace skelcd::ccd {
namespace {

struct Tally {
  int cases = 0;
  int hits = 0;  // exact
  int false_negatives = 0;
  int false_positives = 0;
};

ExactCcdResult exact(const test::HardCase& c) {
  const mpq_class width(1, mpz_class(1) << 50);
  return c.vertex_face ? vertex_face_ccd_rational(to_rational(c.vf()), width)
                       : edge_edge_ccd_rational(to_rational(c.ee()), width);
}

CcdResult run(const test::HardCase& c, Accuracy accuracy, const CcdOptions& options = {}) {
  return c.vertex_face ? vertex_face_ccd(c.vf(), accuracy, options) : edge_edge_ccd(c.ee(), accuracy, options);
}

std::map<std::string, Tally> tally(Accuracy accuracy, const std::vector<test::HardCase>& cases,
                                   bool check_no_false_negative) {
  std::map<std::string, Tally> out;
  for (const auto& c : cases) {
    const auto e = exact(c);
    const auto r = run(c, accuracy);
    auto& t = out[c.family];
    ++t.cases;
    if (e.hit) ++t.hits;
    if (e.hit && !r.hit) ++t.false_negatives;
    if (!e.hit && r.hit) ++t.false_positives;
    if (check_no_false_negative) {
      EXPECT_TRUE(r.hit || !e.hit) << "false negative: " << c.family << " / " << c.variant;
      if (e.hit && r.hit) {
        // toi_lower <= t* <= toi_hi (the exact bracket, 2^-50 wide).
        EXPECT_LE(mpq_class(r.toi_lower), e.toi_hi) << c.family << " / " << c.variant;
        EXPECT_LE(r.toi_lower, r.toi_upper);
      }
    }
  }
  return out;
}

void print(const char* title, const std::map<std::string, Tally>& tallies) {
  std::cout << title << "\n";
  Tally all;
  for (const auto& [family, t] : tallies) {
    std::cout << "  " << std::left << std::setw(22) << family << " cases " << std::setw(5) << t.cases << " hits "
              << std::setw(5) << t.hits << " FN " << std::setw(4) << t.false_negatives << " FP "
              << t.false_positives << "\n";
    all.cases += t.cases;
    all.hits += t.hits;
    all.false_negatives += t.false_negatives;
    all.false_positives += t.false_positives;
  }
  std::cout << "  all: cases " << all.cases << " hits " << all.hits << " FN " << all.false_negatives << " FP "
            << all.false_positives << " (FP rate among misses "
            << 100.0 * all.false_positives / std::max(1, all.cases - all.hits) << "%)\n";
}

TEST(ConservativeCcd, NoFalseNegativeOnAnyHardCaseFamily) {
  const auto cases = test::hard_cases(11, 2);
  const auto tallies = tally(Accuracy::conservative, cases, true);
  print("conservative vs exact on the hard-case families", tallies);
  Tally all;
  for (const auto& [family, t] : tallies) {
    EXPECT_EQ(t.false_negatives, 0) << family;
    all.cases += t.cases;
    all.hits += t.hits;
    all.false_positives += t.false_positives;
  }
  EXPECT_GT(all.hits, 500);
  EXPECT_GT(all.cases - all.hits, 500);
  // Stated false-positive rate (docs/ccd.md, "Measured false positives": 84 of 1,750 misses,
  // 4.8 %): the near misses below the solver's tolerance (relative 1e-10) are reported as hits;
  // everything farther is resolved. Twice the stated rate fails the run.
  EXPECT_LT(all.false_positives, (all.cases - all.hits) / 10);
}

TEST(ConservativeCcd, NearMissesAboveTheToleranceAreResolved) {
  // At relative separation 1e-8 and 1e-9 (above relative_distance_tolerance = 1e-10) no near
  // miss of an exactly built family may come back as a hit.
  const auto cases = test::hard_cases(11, 0);
  int checked = 0;
  for (const auto& c : cases) {
    if (!c.analytic_hit || *c.analytic_hit || !c.separation || *c.separation < 1e-9) continue;
    const auto r = run(c, Accuracy::conservative);
    EXPECT_FALSE(r.hit) << c.family << " / " << c.variant;
    ++checked;
  }
  EXPECT_GT(checked, 150);
}

TEST(ConservativeCcd, MinSeparationCountsNearnessAsContact) {
  using V = Eigen::Vector3d;
  // Vertex gliding over the face at height 1/2.
  const VertexFaceQuery vf{V(0.2, 0.2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                           V(0.3, 0.2, 0.5), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  CcdOptions options;
  options.min_separation = 0.5;  // exactly the distance: touching counts
  EXPECT_TRUE(vertex_face_ccd(vf, Accuracy::conservative, options).hit);
  options.min_separation = 0.6;
  EXPECT_TRUE(vertex_face_ccd(vf, Accuracy::conservative, options).hit);
  options.min_separation = 0.25;
  EXPECT_FALSE(vertex_face_ccd(vf, Accuracy::conservative, options).hit);
  // Parallel edges 1/4 apart, sliding along each other.
  const EdgeEdgeQuery ee{V(0, 0, 0.25), V(1, 0, 0.25), V(0, 0, 0), V(1, 0, 0),
                         V(0.5, 0, 0.25), V(1.5, 0, 0.25), V(0, 0, 0), V(1, 0, 0)};
  options.min_separation = 0.25;
  EXPECT_TRUE(edge_edge_ccd(ee, Accuracy::conservative, options).hit);
  options.min_separation = 0.1;
  EXPECT_FALSE(edge_edge_ccd(ee, Accuracy::conservative, options).hit);
  // Approaching: the vertex falls from 1 to 0.1 above the face; with separation 0.4 the first
  // time within 0.4 is t = 2/3, and toi_lower must not be later.
  const VertexFaceQuery fall{V(0.2, 0.2, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                             V(0.2, 0.2, 0.1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  options.min_separation = 0.4;
  const auto r = vertex_face_ccd(fall, Accuracy::conservative, options);
  ASSERT_TRUE(r.hit);
  EXPECT_LE(r.toi_lower, 2.0 / 3.0);
  EXPECT_GT(r.toi_upper, 2.0 / 3.0 - 1e-5);
}

TEST(ConservativeCcd, NonFiniteInputIsTheSafeAnswer) {
  using V = Eigen::Vector3d;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const VertexFaceQuery q{V(nan, 0, 0), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                          V(0, 0, 0),   V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  EXPECT_TRUE(vertex_face_ccd(q).hit);
}

TEST(ConservativeCcd, IterationLimitIsReportedAsAHit) {
  using V = Eigen::Vector3d;
  // Diving through the plane 2e-3 outside edge ab, with min_separation 1e-3: the swept boxes
  // overlap and the coplanarity filter cannot help, so only the inclusion solver can tell, and it
  // needs more than 3 boxes.
  const VertexFaceQuery q{V(0.5, -1 - 2e-3, 1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0),
                          V(0.5, 1 - 2e-3, -1), V(0, 0, 0), V(1, 0, 0), V(0, 1, 0)};
  CcdOptions options;
  options.min_separation = 1e-3;
  CcdStats stats;
  EXPECT_FALSE(vertex_face_ccd(q, Accuracy::conservative, options, stats).hit);
  EXPECT_EQ(stats.solver_runs, 1);
  EXPECT_GT(stats.solver_boxes, 3);
  options.max_iterations = 3;
  const auto r = vertex_face_ccd(q, Accuracy::conservative, options);
  EXPECT_TRUE(r.hit);
  EXPECT_EQ(r.status, CcdStatus::iteration_limit);
  EXPECT_GE(r.toi_lower, 0.0);
  EXPECT_LE(r.toi_lower, r.toi_upper);
}

TEST(ConservativeCcd, StatsAccountForEveryQuery) {
  const auto cases = test::hard_cases(5, 1);
  CcdStats stats;
  int hits = 0;
  for (const auto& c : cases) {
    const auto r = c.vertex_face ? vertex_face_ccd(c.vf(), Accuracy::conservative, {}, stats)
                                 : edge_edge_ccd(c.ee(), Accuracy::conservative, {}, stats);
    hits += r.hit ? 1 : 0;
  }
  EXPECT_EQ(stats.queries, static_cast<std::int64_t>(cases.size()));
  EXPECT_EQ(stats.hits, hits);
  EXPECT_EQ(stats.aabb_rejected + stats.coplanarity_rejected + stats.algebraic_rejected + stats.algebraic_hits +
                stats.solver_runs,
            stats.queries);
  EXPECT_EQ(stats.algebraic_hits + stats.solver_runs - stats.solver_rejected, stats.hits);
  EXPECT_GT(stats.algebraic_rejected, 0);
  EXPECT_GT(stats.algebraic_hits, 0);
  EXPECT_GT(stats.aabb_rejected, 0);
  EXPECT_GT(stats.coplanarity_rejected, 0);
  EXPECT_GT(stats.solver_rejected, 0);
  EXPECT_GE(stats.solver_boxes, stats.solver_runs);
}

TEST(FastCcd, MissesContactsTheBenchmarkCanSee) {
  const auto cases = test::hard_cases(11, 2);
  const auto tallies = tally(Accuracy::fast, cases, false);
  print("fast vs exact on the hard-case families", tallies);
  // Coplanar motion is invisible to a coplanarity-root method.
  EXPECT_GT(tallies.at("vf/coplanar-motion").false_negatives, 0);
  EXPECT_GT(tallies.at("ee/collinear").false_negatives, 0);
  int total = 0;
  for (const auto& [family, t] : tallies) total += t.false_negatives;
  EXPECT_GT(total, 50);
}

TEST(ExactAccuracy, ThroughTheCommonInterfaceMatchesTheReference) {
  const auto cases = test::hard_cases(3, 0);
  for (const auto& c : cases) {
    const auto e = exact(c);
    const auto r = run(c, Accuracy::exact);
    ASSERT_EQ(r.hit, e.hit) << c.family << " / " << c.variant;
    if (r.hit) {
      EXPECT_LE(mpq_class(r.toi_lower), e.toi_hi);
      EXPECT_GE(mpq_class(r.toi_upper), e.toi_lo);
    }
  }
}

}  // namespace
}  // namespace skelcd::ccd
