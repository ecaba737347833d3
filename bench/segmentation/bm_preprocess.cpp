// Preprocess time and quality of the segmentation (paper 002, Table 1 columns): heat vs rig
// weights, exact vs coarse distance, on generated rigs (rope 10k–200k triangles, octopus, hand)
// and on the real characters. Counters: triangles, weights_s, decomposition_ms, atomic clusters,
// |H⁻|, |Hᵘ| (rest pose), vertices that saw no bone.
//
//   SKELCD_THREADS=1 build/bench/segmentation/bm_segmentation_preprocess --benchmark_counters_tabular=true

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include "segmentation/segmentation.hpp"
#include "skinning/load.hpp"
#include "skinning/generators.hpp"

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

// Generated rigs (skinning/generators.hpp) by name and size, built once.
const skelcd::skinning::Rig& generated(const char* name, std::int64_t triangles) {
  static std::map<std::pair<std::string, std::int64_t>, std::unique_ptr<skelcd::skinning::Rig>> cache;
  auto& slot = cache[{name, triangles}];
  if (!slot) {
    slot = std::make_unique<skelcd::skinning::Rig>(
        skelcd::skinning::generate({name, triangles, 2}).rig);
  }
  return *slot;
}

const char* kGenerators[] = {"rope", "octopus", "hand"};

void BM_Generated(benchmark::State& state) {
  const char* name = kGenerators[state.range(0)];
  const auto& rig = generated(name, state.range(1));
  const auto options = variant(state.range(2));
  seg::Segmentation s;
  for (auto _ : state) {
    s = seg::segment(rig, options);
    benchmark::DoNotOptimize(s.triangle_cluster.data());
  }
  report(state, s, state.range(2));
  state.SetLabel(std::string(name) + " " + variant_name(state.range(2)));
}
// The rope at 10k–200k triangles (48k is the paper's rope), the octopus at the paper's 48k, the
// hand at the paper's 11k.
BENCHMARK(BM_Generated)
    ->ArgsProduct({{0}, {10000, 48000, 100000, 200000}, {0, 1, 2}})
    ->ArgsProduct({{1}, {48000}, {0, 1, 2}})
    ->ArgsProduct({{2}, {11000}, {0, 1, 2}})
    ->ArgNames({"rig", "triangles", "variant"})
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
  // SKELCD_THREADS=1 runs single-threaded, so that the CPU column is all the work done (the
  // parallel parts — distances, per-bone solves, observer choice — otherwise run on worker
  // threads that the CPU column does not count).
  std::unique_ptr<tbb::global_control> threads;
  if (const char* n = std::getenv("SKELCD_THREADS")) {
    threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    static_cast<std::size_t>(std::max(1, std::atoi(n))));
    benchmark::AddCustomContext("threads", n);
  }
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
