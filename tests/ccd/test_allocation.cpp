// The conservative and fast kernels allocate nothing: every global operator new of this test
// executable is counted, and the count must not move while they run (on hits, misses, every stage
// of the pipeline, min_separation > 0, and the iteration limit).

#include <atomic>
#include <cstdlib>
#include <new>

#include <gtest/gtest.h>

#include "ccd/filters.hpp"
#include "ccd/polynomial_sign.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  ++g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace skelcd::ccd {
namespace {

TEST(Allocation, ConservativeAndFastKernelsDoNotAllocate) {
  // Inputs first (they allocate), then the kernels.
  const auto cases = test::hard_cases(13, 1);
  test::RandomQueryGenerator gen(8);
  std::vector<test::RandomQuery> random;
  for (int i = 0; i < 2000; ++i) random.push_back(gen.next());
  CcdOptions separation;
  separation.min_separation = 1e-3;
  CcdOptions tight;
  tight.max_iterations = 5;
  CcdStats stats;
  int hits = 0;
  const long before = g_allocations.load();
  for (const auto& c : cases) {
    for (const CcdOptions& o : {CcdOptions{}, separation, tight}) {
      hits += c.vertex_face ? vertex_face_ccd(c.vf(), Accuracy::conservative, o, stats).hit
                            : edge_edge_ccd(c.ee(), Accuracy::conservative, o, stats).hit;
    }
    hits += c.vertex_face ? vertex_face_ccd(c.vf(), Accuracy::fast).hit : edge_edge_ccd(c.ee(), Accuracy::fast).hit;
  }
  for (const auto& q : random) {
    hits += q.vertex_face ? vertex_face_ccd(q.vf(), Accuracy::conservative, {}, stats).hit
                          : edge_edge_ccd(q.ee(), Accuracy::conservative, {}, stats).hit;
    const MovingOrientationQuery m{q.points[1], q.points[2], q.points[3], q.points[0],
                                   q.points[5], q.points[6], q.points[7], q.points[4]};
    hits += cubic_sign(moving_orientation_cubic(m)) == PolynomialSign::positive;
  }
  const long after = g_allocations.load();
  EXPECT_EQ(after, before);
  // Every stage ran.
  EXPECT_GT(hits, 1000);
  EXPECT_GT(stats.aabb_rejected, 0);
  EXPECT_GT(stats.coplanarity_rejected, 0);
  EXPECT_GT(stats.algebraic_rejected, 0);
  EXPECT_GT(stats.algebraic_hits, 0);
  EXPECT_GT(stats.solver_runs, 0);
  EXPECT_GT(stats.iteration_limit, 0);
  // And the counter does count.
  auto* probe = new int(3);
  EXPECT_EQ(g_allocations.load(), after + 1);
  delete probe;
}

}  // namespace
}  // namespace skelcd::ccd
