// Culling cost per interval (CCD) and per instant (DCD) for `bvh`, `kdop` and `brute` on a
// generated moving, deforming tube from 1k to 200k triangles: one iteration = one detect_ccd
// (refit + traversal + feature stage + conservative elementary tests) or one detect_dcd. Counters
// are per interval: bounding-volume tests, candidate triangle pairs, feature-pair volume tests,
// VF/EE tests, contacts, and ms per stage.
//
//   build/bench/culling/bm_culling --benchmark_counters_tabular=true
//
// The tube: radius 0.4, length 4, triangles of roughly equal size at every resolution (so the
// same motion covers more triangles at finer resolutions, as it would for a denser character
// mesh). Motion: test::deformed — a twist about the tube's axis growing along it plus a
// travelling lateral wave — sampled at 30 Hz (s advances by 1/30 per interval).

#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include "culling/method.hpp"
#include "tests/culling/procedural_meshes.hpp"

namespace {

using namespace skelcd;

struct TubeMotion {
  skinning::Mesh mesh;
  skinning::Topology topology;
  std::vector<skinning::Positions> frames;  // welded positions at s = k / 30
};

/// A tube of about `triangles` triangles and 5 frames of its motion (4 intervals).
const TubeMotion& tube_motion(int triangles) {
  static std::map<int, std::unique_ptr<TubeMotion>> cache;
  auto& slot = cache[triangles];
  if (slot) return *slot;
  slot = std::make_unique<TubeMotion>();
  const double h = std::sqrt(2.0 * 2.0 * 3.14159 * 0.4 * 4.0 / triangles);  // edge length
  const int around = std::max(8, static_cast<int>(std::lround(2.0 * 3.14159 * 0.4 / h)));
  const int along = std::max(2, triangles / (2 * around));
  slot->mesh = test::tube(around, along, 0.4, 4.0);
  slot->topology = test::simple_topology(slot->mesh);
  const auto rest = test::welded(slot->topology, slot->mesh.rest_positions);
  for (int k = 0; k < 5; ++k) slot->frames.push_back(test::deformed(rest, 1.0 + k / 30.0, 1.0));
  return *slot;
}

/// Built methods, cached across the benchmark's repeated invocations.
culling::CullingMethod& method(const std::string& name, int triangles, int leaf_size) {
  static std::map<std::tuple<std::string, int, int>, std::unique_ptr<culling::CullingMethod>> cache;
  auto& slot = cache[{name, triangles, leaf_size}];
  if (!slot) {
    const TubeMotion& m = tube_motion(triangles);
    culling::MethodOptions options;
    options.bvh.leaf_size = leaf_size;
    slot = culling::make_method(name, m.mesh, m.topology, options);
  }
  return *slot;
}

void report(benchmark::State& state, const culling::FrameResult& sum, std::int64_t n) {
  const auto avg = [n](double v) { return v / static_cast<double>(n); };
  const auto& c = sum.counters;
  state.counters["bv_tests"] = avg(static_cast<double>(c.bv_tests));
  state.counters["cand_pairs"] = avg(static_cast<double>(c.candidate_pairs));
  state.counters["feat_bv"] = avg(static_cast<double>(c.feature_bv_tests));
  state.counters["vf+ee"] = avg(static_cast<double>(c.vf_tests + c.ee_tests));
  state.counters["tt"] = avg(static_cast<double>(c.tt_tests));
  state.counters["contacts"] =
      avg(static_cast<double>(c.vf_contacts + c.ee_contacts + c.dcd_pairs));
  state.counters["refit_ms"] = avg(sum.times.refit_us) / 1e3;
  state.counters["trav_ms"] = avg(sum.times.traverse_us) / 1e3;
  state.counters["elem_ms"] = avg(sum.times.elementary_us) / 1e3;
}

void accumulate(culling::FrameResult& sum, const culling::FrameResult& r) {
  sum.counters += r.counters;
  sum.times += r.times;
}

void bm_ccd(benchmark::State& state, const std::string& name) {
  const int triangles = static_cast<int>(state.range(0));
  const int leaf = static_cast<int>(state.range(1));
  const TubeMotion& m = tube_motion(triangles);
  culling::CullingMethod& cm = method(name, triangles, leaf);
  culling::FrameResult r, sum;
  cm.detect_ccd(m.frames[0], m.frames[1], r);  // warm-up: buffers reach their size
  std::size_t i = 0;
  std::int64_t n = 0;
  for (auto _ : state) {
    r.clear();
    cm.detect_ccd(m.frames[i], m.frames[i + 1], r);
    benchmark::DoNotOptimize(r.contacts.data());
    accumulate(sum, r);
    ++n;
    i = (i + 1) % (m.frames.size() - 1);
  }
  report(state, sum, n);
  state.SetItemsProcessed(state.iterations() * m.mesh.triangles.rows());
  state.SetLabel(std::to_string(m.mesh.triangles.rows()) + " triangles");
}

void bm_dcd(benchmark::State& state, const std::string& name) {
  const int triangles = static_cast<int>(state.range(0));
  const int leaf = static_cast<int>(state.range(1));
  const TubeMotion& m = tube_motion(triangles);
  culling::CullingMethod& cm = method(name, triangles, leaf);
  culling::FrameResult r, sum;
  cm.detect_dcd(m.frames[0], r);
  std::size_t i = 0;
  std::int64_t n = 0;
  for (auto _ : state) {
    r.clear();
    cm.detect_dcd(m.frames[i], r);
    benchmark::DoNotOptimize(r.dcd_pairs.data());
    accumulate(sum, r);
    ++n;
    i = (i + 1) % m.frames.size();
  }
  report(state, sum, n);
  state.SetItemsProcessed(state.iterations() * m.mesh.triangles.rows());
  state.SetLabel(std::to_string(m.mesh.triangles.rows()) + " triangles");
}

const std::vector<std::int64_t> kSizes{1'000, 4'000, 16'000, 64'000, 200'000};
const std::vector<std::int64_t> kBruteSizes{1'000, 4'000};

int register_all() {
  benchmark::AddCustomContext(
#ifdef NDEBUG
      "build_type", "release (NDEBUG)"
#else
      "build_type", "asserts on"
#endif
  );
  for (const char* name : {"bvh", "kdop", "brute"}) {
    const auto& sizes = std::string(name) == "brute" ? kBruteSizes : kSizes;
    for (const auto* kind : {"ccd", "dcd"}) {
      auto* b = benchmark::RegisterBenchmark(
          (std::string("BM_") + kind + "/" + name).c_str(), [name, kind](benchmark::State& s) {
            std::string(kind) == "ccd" ? bm_ccd(s, name) : bm_dcd(s, name);
          });
      for (const auto n : sizes) b->Args({n, 1});
      b->ArgNames({"tris", "leaf"})->Unit(benchmark::kMillisecond);
    }
  }
  // Leaf size of the hierarchy methods (the default is 1).
  for (const char* name : {"bvh", "kdop"}) {
    auto* b = benchmark::RegisterBenchmark(
        (std::string("BM_ccd_leaf/") + name).c_str(),
        [name](benchmark::State& s) { bm_ccd(s, name); });
    for (const int leaf : {1, 2, 4, 8}) b->Args({64'000, leaf});
    b->ArgNames({"tris", "leaf"})->Unit(benchmark::kMillisecond);
  }
  return 0;
}

[[maybe_unused]] const int kRegistered = register_all();

}  // namespace

BENCHMARK_MAIN();
