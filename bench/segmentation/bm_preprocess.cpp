// Preprocess time and quality of the segmentation (paper 002, Table 1 columns): heat vs rig
// weights, exact vs coarse distance, on generated bent rope-like rigs from 10k to 200k triangles
// and on the real characters. Counters: triangles, weights_s, decomposition_ms, atomic clusters,
// |H⁻|, |Hᵘ| (rest pose), vertices that saw no bone.
//
//   build-seg/bench/segmentation/bm_segmentation_preprocess --benchmark_counters_tabular=true

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "segmentation/segmentation.hpp"
#include "skinning/load.hpp"
#include "tests/segmentation/mini_rigs.hpp"

namespace {

namespace seg = skelcd::segmentation;

// Weights × distance variants: 0 heat/exact, 1 heat/coarse, 2 rig.
seg::SegmentationOptions variant(std::int64_t v) {
  seg::SegmentationOptions o;
  o.weights = v == 2 ? seg::WeightSource::rig : seg::WeightSource::heat;
  o.heat.distance = v == 1 ? seg::DistanceMode::coarse : seg::DistanceMode::exact;
  return o;
}

const char* variant_name(std::int64_t v) {
  return v == 0 ? "heat/exact" : (v == 1 ? "heat/coarse" : "rig");
}

void report(benchmark::State& state, const seg::Segmentation& s, std::int64_t v) {
  state.counters["triangles"] = static_cast<double>(s.stats.triangles);
  state.counters["weights_s"] = s.stats.weights_s;
  state.counters["decomp_ms"] = s.stats.decomposition_ms;
  state.counters["clusters"] = s.stats.atomic_clusters;
  state.counters["H-"] = static_cast<double>(s.stats.h_minus);
  state.counters["Hu"] = static_cast<double>(s.stats.h_uncertain);
  state.counters["dist_s"] = s.stats.heat.distance_s;
  state.counters["factor_s"] = s.stats.heat.factorize_s;
  state.counters["solve_s"] = s.stats.heat.solve_s;
  state.counters["no_bone"] = static_cast<double>(s.stats.heat.fallback_vertices);
  state.counters["triangles/s"] = benchmark::Counter(
      static_cast<double>(s.stats.triangles), benchmark::Counter::kIsIterationInvariantRate);
  state.SetLabel(variant_name(v));
}

// A 20-bone rope bent 30° at every joint (zigzag), 48 sides, about `ktri` thousand triangles.
std::shared_ptr<const skelcd::skinning::Rig> rope(std::int64_t ktri) {
  static std::map<std::int64_t, std::shared_ptr<const skelcd::skinning::Rig>> cache;
  auto& slot = cache[ktri];
  if (!slot) {
    const int bones = 20, sides = 48;
    const int rings_per_bone =
        std::max(2, static_cast<int>(ktri * 1000 / (2 * sides * bones)));
    slot = std::make_shared<const skelcd::skinning::Rig>(
        skelcd::test::bent_capsule_chain(bones, 30.0, true, 0.2, rings_per_bone, sides));
  }
  return slot;
}

void BM_GeneratedRope(benchmark::State& state) {
  const auto rig = rope(state.range(0));
  const auto options = variant(state.range(1));
  seg::Segmentation s;
  for (auto _ : state) {
    s = seg::segment(*rig, options);
    benchmark::DoNotOptimize(s.triangle_cluster.data());
  }
  report(state, s, state.range(1));
}
BENCHMARK(BM_GeneratedRope)
    ->ArgsProduct({{10, 25, 50, 100, 200}, {0, 1, 2}})
    ->ArgNames({"ktri", "variant"})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

const char* kCharacters[] = {"assets/characters/CesiumMan.glb",
                             "/usr/share/assimp/models/X/BCN_Epileptic.X",
                             "assets/characters/Fox.glb"};

void BM_RealCharacter(benchmark::State& state) {
  std::filesystem::path path = kCharacters[state.range(0)];
  if (path.is_relative()) path = std::filesystem::path(SKELCD_SOURCE_DIR) / path;
  const auto model = skelcd::skinning::load_model(path);
  const auto options = variant(state.range(1));
  seg::Segmentation s;
  for (auto _ : state) {
    s = seg::segment(*model.rig, options);
    benchmark::DoNotOptimize(s.triangle_cluster.data());
  }
  report(state, s, state.range(1));
  state.SetLabel(path.filename().string() + " " + variant_name(state.range(1)));
}
BENCHMARK(BM_RealCharacter)
    ->ArgsProduct({{0, 1, 2}, {0, 1, 2}})
    ->ArgNames({"model", "variant"})
    ->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
#ifdef NDEBUG
  benchmark::AddCustomContext("asserts", "off (NDEBUG)");
#else
  benchmark::AddCustomContext("asserts", "on: not a release build, timings are not comparable");
#endif
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
