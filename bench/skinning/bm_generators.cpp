// Generators: build time per size (triangles/s), and the long known-answer run — every frame of
// the default 60-frame clips checked with the exact brute-force reference of the tests (too slow
// for ctest's default label). A frame that contradicts the known answer fails the run.
//
//   build/bench/skinning/bm_generators --benchmark_filter=Generate
//   build/bench/skinning/bm_generators --benchmark_filter=KnownAnswer

#include <benchmark/benchmark.h>

#include <memory>
#include <string>

#include "skinning/generators.hpp"
#include "skinning/rig_motion.hpp"
#include "tests/skinning/test_generators_exact.hpp"

namespace {

using namespace skelcd;

const char* const kNames[] = {"rope", "octopus", "hand", "pipe", "cloth"};

skinning::GeneratorSpec spec(std::int64_t name, std::int64_t triangles, int frames) {
  skinning::GeneratorSpec s;
  s.name = kNames[name];
  s.triangles = triangles;
  s.frames = frames;
  return s;
}

// Generation (mesh, skeleton, weights, clip and the per-frame known-answer margins) of 60 frames.
void BM_Generate(benchmark::State& state) {
  const auto s = spec(state.range(0), state.range(1), 60);
  std::int64_t triangles = 0;
  for (auto _ : state) {
    const auto g = skinning::generate(s);
    triangles = g.rig.mesh.num_triangles();
    benchmark::DoNotOptimize(g.answer.margin.data());
  }
  state.SetLabel(s.name);
  state.SetItemsProcessed(state.iterations() * triangles);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_Generate)->ArgsProduct({{0, 1, 2, 3, 4}, {1'000, 10'000, 100'000, 200'000}})->Unit(benchmark::kMillisecond);

// Every frame, exactly: frames <= last_free must be free, frames >= first_intersecting must not.
void BM_KnownAnswer(benchmark::State& state) {
  const auto g = skinning::generate(spec(state.range(0), state.range(1), 60));
  auto rig = std::make_shared<const skinning::Rig>(g.rig);
  skinning::RigMotionOptions options;
  options.clip = 0;
  const skinning::RigMotion motion(rig, options);
  int wrong = 0;
  skinning::Positions p;
  for (auto _ : state) {
    wrong = 0;
    for (int i = 0; i < motion.num_samples(); ++i) {
      motion.positions(i, p);
      const bool hit = !test::exact::self_intersections(p, g.rig.mesh.triangles, true).pairs.empty();
      if ((i <= g.answer.last_free_frame && hit) || (i >= g.answer.first_intersecting_frame && !hit)) ++wrong;
    }
  }
  state.SetLabel(g.rig.source);
  state.counters["wrong_frames"] = wrong;
  state.SetItemsProcessed(state.iterations() * motion.num_samples());
  if (wrong > 0) state.SkipWithError("a frame contradicts the known answer");
}
BENCHMARK(BM_KnownAnswer)->ArgsProduct({{0, 1, 2, 3, 4}, {1'000, 10'000}})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

BENCHMARK_MAIN();
