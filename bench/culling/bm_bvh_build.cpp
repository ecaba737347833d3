// Cost of building the hierarchy (culling::Bvh, the surface-area split) on real meshes: what
// every method pays once per check before its first query, on the serial start of a parallel
// check (docs/benchmarks.md, "parallel"). One iteration = one Bvh<3> built over every welded
// triangle at the first sample, as `bvh`, `dynamic` and `auto` build it (no binary node volumes);
// Bvh<8> as `kdop` builds it; BM_features: the mesh's culling::FeatureTopology; BM_certify: its
// vertex fans certified at that sample (VertexFans::certify, once per DCD instant), labelled with
// how many are certified and a hash of which.
//
//   build/bench/culling/bm_bvh_build [MODEL …] [--benchmark_* flags]
//
// Without MODEL: the bundled characters and, when present, the cloth steps of
// ../shared/assets/cloth. Each row's label gives the triangles and a hash of the tree (the node
// ranges and the triangle order): two builds of skelcd that label a model alike build the same
// tree, so a faster build can be checked to change nothing else.

#include <benchmark/benchmark.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "culling/bvh.hpp"
#include "culling/feature_topology.hpp"
#include "skinning/load.hpp"
#include "skinning/topology.hpp"

namespace {

using namespace skelcd;

struct Input {
  std::string name;
  skinning::Positions welded;  // at the first sample
  std::shared_ptr<const skinning::Mesh> mesh;
  skinning::Topology topology;
};

constexpr std::uint64_t kFnvBasis = 1469598103934665603ull;

/// One byte into an FNV-1a hash.
inline void fnv_byte(std::uint64_t& h, std::uint8_t byte) {
  h ^= byte;
  h *= 1099511628211ull;
}

/// FNV-1a over the node ranges and the triangle order.
template <int N>
std::uint64_t tree_hash(const culling::Bvh<N>& bvh) {
  std::uint64_t h = kFnvBasis;
  const auto mix = [&h](std::int32_t v) {
    for (int b = 0; b < 4; ++b) {
      fnv_byte(h, static_cast<std::uint8_t>(static_cast<std::uint32_t>(v) >> (8 * b)));
    }
  };
  for (const culling::BvhNode& n : bvh.nodes()) {
    mix(n.begin);
    mix(n.end);
    mix(n.right);
  }
  for (const std::int32_t t : bvh.triangle_order()) mix(t);
  return h;
}

template <int N>
void bm_build(benchmark::State& state, const Input* input) {
  culling::BvhOptions options;
  options.node_volumes = false;
  for (auto _ : state) {
    culling::Bvh<N> bvh(input->topology.welded_triangles, input->welded, options);
    benchmark::DoNotOptimize(bvh.nodes().data());
  }
  const std::uint64_t hash =
      tree_hash(culling::Bvh<N>(input->topology.welded_triangles, input->welded, options));
  char label[96];
  std::snprintf(
      label,
      sizeof label,
      "%lld triangles, tree %016llx",
      static_cast<long long>(input->topology.welded_triangles.rows()),
      static_cast<unsigned long long>(hash));
  state.SetLabel(label);
  state.SetItemsProcessed(state.iterations() * input->topology.welded_triangles.rows());
}

/// The mesh's FeatureTopology (with its vertex fans): what every method, the baseline and each
/// incremental-DCD updater build before their first query.
void bm_features(benchmark::State& state, const Input* input) {
  for (auto _ : state) {
    const culling::FeatureTopology features(*input->mesh, input->topology);
    benchmark::DoNotOptimize(&features);
  }
  state.SetLabel(std::to_string(input->topology.welded_triangles.rows()) + " triangles");
}

/// The vertex fans certified at the first sample: what every DCD instant pays before its traversal.
void bm_certify(benchmark::State& state, const Input* input) {
  const culling::FeatureTopology features(*input->mesh, input->topology);
  std::vector<std::uint8_t> certified;
  for (auto _ : state) {
    features.fans().certify(input->welded, certified);
    benchmark::DoNotOptimize(certified.data());
  }
  std::uint64_t h = kFnvBasis;
  std::size_t count = 0;
  for (const std::uint8_t c : certified) {
    fnv_byte(h, c);
    count += c;
  }
  char label[96];
  std::snprintf(
      label,
      sizeof label,
      "%zu of %zu certified, %016llx",
      count,
      certified.size(),
      static_cast<unsigned long long>(h));
  state.SetLabel(label);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(certified.size()));
}

std::vector<std::string> default_models() {
  const std::filesystem::path source(SKELCD_SOURCE_DIR);
  std::vector<std::string> models;
  for (const char* m :
       {"assets/characters/CesiumMan.glb",
        "assets/characters/RobotExpressive.glb",
        "assets/characters/ninja/ninja.mesh",
        "assets/characters/stormtrooper/stormtrooper.dae"}) {
    if (std::filesystem::exists(source / m)) models.push_back((source / m).string());
  }
  for (const char* c : {"cloth-funnel", "cloth-ball"}) {
    const auto frames = source.parent_path() / "shared/assets/cloth" / c / "frames";
    if (std::filesystem::is_directory(frames)) models.push_back(frames.string());
  }
  return models;
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  std::vector<std::string> models;
  for (int i = 1; i < argc; ++i) models.emplace_back(argv[i]);
  if (models.empty()) models = default_models();
  std::vector<std::unique_ptr<Input>> inputs;
  for (const auto& path : models) {
    try {
      const skinning::LoadedModel model = skinning::load_model(path);
      const auto motion = model.motion({});
      const skinning::Topology topology = skinning::build_topology(motion->mesh());
      skinning::Positions posed;
      motion->positions(0, posed);
      auto input = std::make_unique<Input>();
      input->name = std::filesystem::path(path).filename().string();
      if (input->name == "frames") {
        input->name = std::filesystem::path(path).parent_path().filename().string();
      }
      input->mesh = std::make_shared<const skinning::Mesh>(motion->mesh());
      input->topology = topology;
      skinning::gather_welded(topology, posed, input->welded);
      inputs.push_back(std::move(input));
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bm_bvh_build: %s\n", e.what());
      return 1;
    }
  }
  for (const auto& input : inputs) {
    benchmark::RegisterBenchmark(("BM_build_aabb/" + input->name).c_str(), bm_build<3>, input.get())
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_build_kdop/" + input->name).c_str(), bm_build<8>, input.get())
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_features/" + input->name).c_str(), bm_features, input.get())
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_certify/" + input->name).c_str(), bm_certify, input.get())
        ->Unit(benchmark::kMicrosecond);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
