// What accuracy costs: ns per query for exact, conservative and fast on four sets of CCD queries,
// with false negatives / positives against the exact reference as counters (computed once per
// set, outside the timed loop). Also the triangle-triangle DCD and the moving-orientation cubic.
//
//   build/bench/ccd/bm_ccd --benchmark_counters_tabular=true
//
// Sets: random — 20,000 queries with 8 points uniform in [-1,1]^3; degenerate — the hard-case
// families of tests/ccd (2,672 queries); mixed — the property-test mix of random and
// near-degenerate queries (5,000); cloth — the cloth-funnel step with its ground truth (355).

#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "ccd/exact_ccd.hpp"
#include "ccd/polynomial_sign.hpp"
#include "ccd/triangle_triangle.hpp"
#include "tests/ccd/cloth_funnel.hpp"
#include "tests/ccd/hard_cases.hpp"
#include "tests/ccd/random_queries.hpp"

namespace {

using namespace skelcd::ccd;

struct Query {
  bool vertex_face;
  VertexFaceQuery vf;
  EdgeEdgeQuery ee;
};

struct QuerySet {
  std::vector<Query> queries;
  std::vector<bool> exact_hit;
};

Query from_points(bool vertex_face, const std::array<Eigen::Vector3d, 8>& p) {
  return {vertex_face, {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]}, {p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]}};
}

CcdResult run(const Query& q, Accuracy accuracy) {
  return q.vertex_face ? vertex_face_ccd(q.vf, accuracy) : edge_edge_ccd(q.ee, accuracy);
}

QuerySet build(const std::string& name) {
  QuerySet set;
  if (name == "random") {
    test::RandomQueryGenerator gen(1);
    for (int i = 0; i < 20000; ++i) {
      const auto q = gen.next_uniform();
      set.queries.push_back(from_points(q.vertex_face, q.points));
    }
  } else if (name == "mixed") {
    test::RandomQueryGenerator gen(2);
    for (int i = 0; i < 5000; ++i) {
      const auto q = gen.next();
      set.queries.push_back(from_points(q.vertex_face, q.points));
    }
  } else if (name == "degenerate") {
    for (const auto& c : test::hard_cases(11, 2)) set.queries.push_back(from_points(c.vertex_face, c.points));
  } else {
    for (const char* kind : {"vf", "ee"}) {
      for (const auto& c : test::load_cloth_funnel(kind)) {
        set.queries.push_back(c.vertex_face ? Query{true, c.vf(), {}} : Query{false, {}, c.ee()});
      }
    }
  }
  for (const auto& q : set.queries) set.exact_hit.push_back(run(q, Accuracy::exact).hit);
  return set;
}

const QuerySet& query_set(const std::string& name) {
  static std::map<std::string, std::unique_ptr<QuerySet>> sets;
  auto& s = sets[name];
  if (!s) s = std::make_unique<QuerySet>(build(name));
  return *s;
}

void BM_ccd(benchmark::State& state, const std::string& set_name, Accuracy accuracy) {
  const QuerySet& set = query_set(set_name);
  // Accuracy against the exact reference, once over the whole set.
  std::int64_t hits = 0, exact_hits = 0, fn = 0, fp = 0;
  for (std::size_t i = 0; i < set.queries.size(); ++i) {
    const bool hit = run(set.queries[i], accuracy).hit;
    hits += hit;
    exact_hits += set.exact_hit[i];
    fn += set.exact_hit[i] && !hit;
    fp += !set.exact_hit[i] && hit;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(run(set.queries[i], accuracy));
    if (++i == set.queries.size()) i = 0;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["queries"] = static_cast<double>(set.queries.size());
  state.counters["exact_hits"] = static_cast<double>(exact_hits);
  state.counters["hits"] = static_cast<double>(hits);
  state.counters["FN"] = static_cast<double>(fn);
  state.counters["FP"] = static_cast<double>(fp);
}

void BM_triangles_intersect(benchmark::State& state, bool shared_vertex) {
  // Pairs of triangles with corners in a unit box (about half intersect); with a shared vertex the
  // second triangle starts at the first one's corner 0.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  const auto point = [&] {
    const double x = u(rng), y = u(rng), z = u(rng);
    return Eigen::Vector3d(x, y, z);
  };
  std::vector<TriangleTriangleQuery> pairs;
  for (int i = 0; i < 4096; ++i) {
    TriangleTriangleQuery q{point(), point(), point(), point(), point(), point()};
    if (shared_vertex) q.b0 = q.a0;
    pairs.push_back(q);
  }
  const SharedCorners shared = shared_vertex ? SharedCorners{0, -1, -1} : kNoSharedCorners;
  std::int64_t hits = 0;
  for (const auto& q : pairs) hits += triangles_intersect(q, shared);
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(triangles_intersect(pairs[i], shared));
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["intersecting"] = static_cast<double>(hits) / 4096.0;
}

// The orientation class of a triangle against an observer: `screened` = moving_orientation_sign
// (the coplanarity screen's bound first), else cubic_sign of the full cubic — the same answers.
// `small_motion`: every point moves by at most 0.05 over the interval (a radial-view interval:
// the sign is mostly clear), else t0 and t1 are independent (mostly uncertain).
void BM_moving_orientation(benchmark::State& state, bool screened, bool small_motion) {
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto point = [&] {
    const double x = u(rng), y = u(rng), z = u(rng);
    return Eigen::Vector3d(x, y, z);
  };
  std::vector<MovingOrientationQuery> qs;
  int certain = 0;
  for (int i = 0; i < 4096; ++i) {
    MovingOrientationQuery q;
    for (auto* p : {&q.a_t0, &q.b_t0, &q.c_t0, &q.q_t0}) *p = point();
    q.a_t1 = small_motion ? Eigen::Vector3d(q.a_t0 + 0.05 * point()) : point();
    q.b_t1 = small_motion ? Eigen::Vector3d(q.b_t0 + 0.05 * point()) : point();
    q.c_t1 = small_motion ? Eigen::Vector3d(q.c_t0 + 0.05 * point()) : point();
    q.q_t1 = small_motion ? Eigen::Vector3d(q.q_t0 + 0.05 * point()) : point();
    qs.push_back(q);
    certain += moving_orientation_sign(q) != PolynomialSign::uncertain ? 1 : 0;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    if (screened) {
      benchmark::DoNotOptimize(moving_orientation_sign(qs[i]));
    } else {
      benchmark::DoNotOptimize(cubic_sign(moving_orientation_cubic(qs[i])));
    }
    i = (i + 1) & 4095;
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["certain"] = static_cast<double>(certain) / 4096.0;
}

void register_all() {
  for (const char* set : {"random", "degenerate", "mixed", "cloth"}) {
    for (const Accuracy a : {Accuracy::fast, Accuracy::conservative, Accuracy::exact}) {
      benchmark::RegisterBenchmark(("ccd/" + std::string(set) + "/" + std::string(to_string(a))).c_str(),
                                   [set, a](benchmark::State& s) { BM_ccd(s, set, a); });
    }
  }
  benchmark::RegisterBenchmark("triangles_intersect/random", [](benchmark::State& s) { BM_triangles_intersect(s, false); });
  benchmark::RegisterBenchmark("triangles_intersect/shared_vertex",
                               [](benchmark::State& s) { BM_triangles_intersect(s, true); });
  for (const bool small : {false, true}) {
    const std::string motion = small ? "/small_motion" : "/random";
    benchmark::RegisterBenchmark(
        ("moving_orientation_cubic+cubic_sign" + motion).c_str(),
        [small](benchmark::State& s) { BM_moving_orientation(s, false, small); });
    benchmark::RegisterBenchmark(
        ("moving_orientation_sign" + motion).c_str(),
        [small](benchmark::State& s) { BM_moving_orientation(s, true, small); });
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
#ifdef NDEBUG
  benchmark::AddCustomContext("build", "release (NDEBUG)");
#else
  benchmark::AddCustomContext("build", "debug (asserts on)");
#endif
  register_all();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
