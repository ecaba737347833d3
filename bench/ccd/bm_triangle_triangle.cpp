// ccd::triangles_intersect against the implementation it replaced (tests/ccd/
// triangle_triangle_reference.cpp) on the queries of real DCDs: ns per query, old and new, on the
// pairs `bvh`'s DCD tests at posed frames (those a certified vertex fan settles left out, as the
// DCD leaves them out), and on every candidate pair (`/all`).
//
//   build/bench/ccd/bm_triangle_triangle --benchmark_counters_tabular=true
//
// Sets: RobotExpressive, CesiumMan, the stormtrooper (4 samples over the first clip each), the
// cloth-funnel step and, when ../shared/assets is there, the cloth-ball step (2 frames each).
// Each set is loaded once, when its first benchmark runs; a disagreement between the two
// implementations stops the run with a non-zero exit.

#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "ccd/triangle_triangle.hpp"
#include "tests/ccd/triangle_triangle_reference.hpp"
#include "tests/culling/real_triangle_queries.hpp"

namespace {

using namespace skelcd;
using culling::test::RecordedTriangleQuery;

struct Set {
  std::string name;
  std::filesystem::path path;
  int samples;
};

const std::vector<Set>& sets() {
  static const std::vector<Set> all = [] {
    const std::filesystem::path root(SKELCD_SOURCE_DIR);
    std::vector<Set> s{
        {"RobotExpressive", root / "assets/characters/RobotExpressive.glb", 4},
        {"CesiumMan", root / "assets/characters/CesiumMan.glb", 4},
        {"stormtrooper", root / "assets/characters/stormtrooper/stormtrooper.dae", 4},
        {"cloth-funnel", root / "assets/cloth-funnel/frames", 2},
    };
    const auto ball = root.parent_path() / "shared/assets/cloth/cloth-ball/frames";
    if (std::filesystem::exists(ball)) s.push_back({"cloth-ball", ball, 2});
    return s;
  }();
  return all;
}

// The queries of a set: the tested ones (production) or every candidate pair.
const std::vector<RecordedTriangleQuery>& queries(const Set& set, bool all) {
  static std::map<std::string, std::vector<RecordedTriangleQuery>> cache;
  const std::string key = set.name + (all ? "/all" : "");
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const auto recorded = culling::test::record_dcd_queries(set.path, set.samples);
  std::vector<RecordedTriangleQuery> tested, every;
  for (const auto& r : recorded.queries) {
    every.push_back(r);
    if (!r.fan_settled) tested.push_back(r);
    if (ccd::triangles_intersect(r.query, r.shared) !=
        ccd::reference::triangles_intersect_reference(r.query, r.shared)) {
      std::fprintf(stderr, "%s: the new test disagrees with the reference\n", set.name.c_str());
      std::exit(1);
    }
  }
  if (static_cast<std::int64_t>(tested.size()) != recorded.production_tests) {
    std::fprintf(
        stderr,
        "%s: %zu unsettled queries recorded, the DCD tested %lld\n",
        set.name.c_str(),
        tested.size(),
        static_cast<long long>(recorded.production_tests));
  }
  cache[set.name] = std::move(tested);
  cache[set.name + "/all"] = std::move(every);
  return cache[key];
}

template <bool kReference>
void BM_real(benchmark::State& state, const Set& set, bool all) {
  const auto& qs = queries(set, all);
  std::int64_t hits = 0;
  for (auto _ : state) {
    for (const auto& r : qs) {
      const bool hit = kReference ? ccd::reference::triangles_intersect_reference(r.query, r.shared)
                                  : ccd::triangles_intersect(r.query, r.shared);
      hits += hit ? 1 : 0;
    }
    benchmark::ClobberMemory();
  }
  const auto n = static_cast<double>(qs.size());
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(qs.size()));
  state.counters["queries"] = n;
  state.counters["hits"] = static_cast<double>(hits) / static_cast<double>(state.iterations());
  // Seconds per query (printed with an SI prefix: "61.8n" is 61.8 ns).
  state.counters["per_query"] = benchmark::Counter(
      n, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void register_all() {
  for (const Set& set : sets()) {
    for (const bool all : {false, true}) {
      const std::string base = "triangles_intersect/" + set.name + (all ? "/all" : "");
      benchmark::RegisterBenchmark((base + "/old").c_str(), [&set, all](benchmark::State& s) {
        BM_real<true>(s, set, all);
      })->Unit(benchmark::kMillisecond);
      benchmark::RegisterBenchmark((base + "/new").c_str(), [&set, all](benchmark::State& s) {
        BM_real<false>(s, set, all);
      })->Unit(benchmark::kMillisecond);
    }
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
