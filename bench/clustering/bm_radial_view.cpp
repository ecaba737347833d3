// Radial-view culling on whole clips (paper 002, Tables 2 and 3): for each scene, `bvh` (AABB),
// `kdop` (16-DOP), `rvbc` and `dynamic` run every interval of the clip; the contacts of every
// method must equal those of `bvh` (a mismatch fails the run, exit code 1). Printed per scene:
// ms per interval excluding refit (Z − Z_r), bounding-volume overlap tests (BVOT) and potentially
// colliding triangle pairs (PCTP) per interval, their ratios to `bvh`, the speedups, and the
// Table 3 columns (RV-update = classify + merge, traversal, elementary tests, |H⁻|, |Hᵘ|,
// atomic / mega clusters).
//
//   build-rv/bench/clustering/bm_radial_view                 # the table (all scenes)
//   build-rv/bench/clustering/bm_radial_view --scenes=rope,hand --intervals=20
//   build-rv/bench/clustering/bm_radial_view --scenes=rope,octopus --first=34 --intervals=20
//                                       # samples 34..54: the window where the limbs first touch
//   build-rv/bench/clustering/bm_radial_view --benchmark      # Google Benchmark per interval
//
// Scenes: the generated clips at the paper's sizes (rope-like 48k, hand-like 11k, octopus-like
// 48k triangles; there is no man generator: the man-like row is the real characters) and the real
// characters in assets/characters and BCN_Epileptic.X.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "skinning/generators.hpp"
#include "skinning/load.hpp"
#include "tests/clustering/radial_view_fixture.hpp"

namespace {

namespace sk = skelcd::skinning;
using skelcd::test::ClipRun;
using skelcd::test::RadialViewScene;

struct SceneSpec {
  std::string name;
  std::string model;  ///< gen: spec or a path
  std::int32_t clip = 0;  ///< −1: every clip
};

std::vector<SceneSpec> all_scenes() {
  const std::string src = SKELCD_SOURCE_DIR;
  return {
      {"rope", "gen:rope?triangles=48000&frames=60"},
      {"hand", "gen:hand?triangles=11000&frames=60"},
      {"octopus", "gen:octopus?triangles=48000&frames=60"},
      {"panda", "gen:panda"},
      {"pipe", "gen:pipe?triangles=20000&frames=60"},
      {"cloth", "gen:cloth?triangles=20000&frames=60"},
      {"CesiumMan", src + "/assets/characters/CesiumMan.glb", -1},
      {"RiggedFigure", src + "/assets/characters/RiggedFigure.glb", -1},
      {"Fox", src + "/assets/characters/Fox.glb", -1},
      {"RobotExpressive", src + "/assets/characters/RobotExpressive.glb", -1},
      {"BCN_Epileptic", "/usr/share/assimp/models/X/BCN_Epileptic.X", -1},
  };
}

std::shared_ptr<const sk::Rig> load_rig(const std::string& model) {
  if (sk::is_generator_spec(model)) {
    auto g = sk::generate(sk::parse_generator_spec(model));
    return std::make_shared<const sk::Rig>(std::move(g.rig));
  }
  return sk::load_model(model).rig;
}

struct MethodTotals {
  double ms_total = 0, ms_refit = 0, ms_classify = 0, ms_merge = 0, ms_traverse = 0,
         ms_elementary = 0;
  double bv_tests = 0, pctp = 0, h_minus = 0, h_uncertain = 0, atomic = 0, mega = 0;
  std::int64_t mega_min = 0, mega_max = 0;
  std::int64_t intervals = 0;
  std::size_t contacts = 0;
  bool agrees = true;
};

MethodTotals summarize(const ClipRun& run) {
  MethodTotals t;
  t.intervals = static_cast<std::int64_t>(run.frames.size());
  for (const double ms : run.ccd_ms) t.ms_total += ms;
  t.mega_min = std::numeric_limits<std::int64_t>::max();
  for (const auto& f : run.frames) {
    t.ms_refit += f.times.refit_us / 1000;
    t.ms_classify += f.times.classify_us / 1000;
    t.ms_merge += f.times.merge_us / 1000;
    t.ms_traverse += f.times.traverse_us / 1000;
    t.ms_elementary += f.times.elementary_us / 1000;
    t.bv_tests += static_cast<double>(f.counters.bv_tests);
    t.pctp += static_cast<double>(f.counters.candidate_pairs);
    t.h_minus += static_cast<double>(f.counters.h_minus);
    t.h_uncertain += static_cast<double>(f.counters.h_uncertain);
    t.atomic += static_cast<double>(f.counters.atomic_clusters);
    t.mega += static_cast<double>(f.counters.mega_clusters);
    t.mega_min = std::min(t.mega_min, f.counters.mega_clusters);
    t.mega_max = std::max(t.mega_max, f.counters.mega_clusters);
  }
  t.contacts = run.contacts.size();
  return t;
}

int run_table(
    const std::vector<SceneSpec>& scenes, std::int32_t first_sample, std::int32_t max_intervals) {
  const std::vector<std::string> methods = {"bvh", "kdop", "rvbc", "dynamic"};
  int failures = 0;
  std::printf(
      "| scene | tris | intervals | method | ms/interval (Z−Zr) | refit ms | RV-update ms | "
      "traverse ms | ET ms | BVOT/int | PCTP/int | BVOT/bvh | PCTP/bvh | speedup vs bvh | "
      "speedup vs kdop | |H⁻| | |Hᵘ| | atomic | mega [min,max] | contacts |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& scene_spec : scenes) {
    std::fprintf(stderr, "[%s] loading %s\n", scene_spec.name.c_str(), scene_spec.model.c_str());
    const auto rig = load_rig(scene_spec.model);
    if (!rig || rig->clips.empty()) {
      std::fprintf(stderr, "[%s] no rig or no clip: skipped\n", scene_spec.name.c_str());
      continue;
    }
    // clip −1: every clip of the model, one table block each.
    std::vector<std::int32_t> clips;
    if (scene_spec.clip >= 0) {
      clips.push_back(scene_spec.clip);
    } else {
      for (std::size_t c = 0; c < rig->clips.size(); ++c) clips.push_back(static_cast<std::int32_t>(c));
    }
    for (const std::int32_t clip : clips) {
    SceneSpec spec = scene_spec;
    spec.clip = clip;
    if (clips.size() > 1) spec.name += "/" + rig->clips[static_cast<std::size_t>(clip)].name;
    const auto seg_start = std::chrono::steady_clock::now();
    RadialViewScene scene(rig, spec.clip);
    const double seg_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - seg_start).count();
    const std::int32_t samples = scene.motion->num_samples();
    // Samples first..last (a clip shorter than `first_sample` is run from its start).
    const std::int32_t first = first_sample < samples - 1 ? first_sample : 0;
    const std::int32_t last =
        max_intervals > 0 ? std::min(samples - 1, first + max_intervals) : samples - 1;
    std::fprintf(
        stderr,
        "[%s] %lld triangles, samples %d..%d (%d intervals), segmentation %.2f s (rig "
        "weights)\n",
        spec.name.c_str(),
        static_cast<long long>(rig->mesh.num_triangles()),
        first,
        last,
        last - first,
        seg_s);
    std::map<std::string, MethodTotals> totals;
    ClipRun reference;
    for (const auto& name : methods) {
      auto method = scene.method(name);
      const auto start = std::chrono::steady_clock::now();
      // As `check` does by default, a DCD at the first sample precedes the CCD intervals (not
      // timed here: every method's DCD is bvh's); the radial-view methods learn from it which
      // components are free of self-intersection at the start.
      ClipRun run =
          skelcd::test::run_clip(scene, *method, first, last, skelcd::test::DcdQueries::first);
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
              .count();
      MethodTotals t = summarize(run);
      if (name == "bvh") {
        reference = run;
      } else if (run.contacts != reference.contacts) {
        t.agrees = false;
        ++failures;
        std::fprintf(stderr, "[%s] %s: %zu contacts, bvh %zu: MISMATCH\n", spec.name.c_str(),
                     name.c_str(), run.contacts.size(), reference.contacts.size());
      }
      totals[name] = t;
      std::int64_t dcd = 0, dirty = 0, escalated = 0, retested = 0, culled = 0, rel = 0;
      for (const auto& st : run.stats) {
        dcd += st.components_dcd;
        dirty += st.components_dirty;
        escalated += st.components_escalated;
        retested += st.skipped_pairs_retested;
        culled += st.components_culled;
        rel += st.relative_aabb_culled;
      }
      std::fprintf(stderr,
                   "[%s] %s done (%.1f ms); component-intervals: culled %lld, DCD-checked %lld, "
                   "dirty %lld, escalated %lld (%lld skipped pairs re-tested); relative AABB "
                   "removed %lld pairs\n",
                   spec.name.c_str(), name.c_str(), ms, static_cast<long long>(culled),
                   static_cast<long long>(dcd), static_cast<long long>(dirty),
                   static_cast<long long>(escalated), static_cast<long long>(retested),
                   static_cast<long long>(rel));
    }
    {
      // The bare argument, without the guard (no precondition pass, no re-test after a
      // self-contact): how many of the contacts it finds on this clip. Not a method anyone
      // should use; the measurement behind docs/radial-view.md ("Preconditions").
      skelcd::clustering::RadialViewOptions bare;
      bare.guard = false;
      skelcd::clustering::RadialViewMethod method(
          "dynamic",
          rig->mesh,
          scene.topology,
          scene.segmentation,
          scene.poses,
          rig->skeleton.num_bones(),
          scene.options(),
          bare);
      const ClipRun run = skelcd::test::run_clip(scene, method, first, last);
      std::vector<skelcd::test::ContactKey> missed, extra;
      std::set_difference(reference.contacts.begin(), reference.contacts.end(),
                          run.contacts.begin(), run.contacts.end(), std::back_inserter(missed));
      std::set_difference(run.contacts.begin(), run.contacts.end(), reference.contacts.begin(),
                          reference.contacts.end(), std::back_inserter(extra));
      std::fprintf(stderr,
                   "[%s] bare dynamic (no guard): finds %zu of %zu contacts (%zu missed, %zu "
                   "not in bvh)\n",
                   spec.name.c_str(), reference.contacts.size() - missed.size(),
                   reference.contacts.size(), missed.size(), extra.size());
      if (!extra.empty()) ++failures;  // never a contact bvh does not have
    }
    const auto& b = totals["bvh"];
    const auto& k = totals["kdop"];
    const auto query_ms = [](const MethodTotals& t) {
      return (t.ms_total - t.ms_refit) / static_cast<double>(t.intervals);
    };
    for (const auto& name : methods) {
      const auto& t = totals[name];
      const double n = static_cast<double>(t.intervals);
      char mega[64] = "–";
      if (t.mega > 0) {
        std::snprintf(mega, sizeof mega, "%.1f [%lld,%lld]", t.mega / n,
                      static_cast<long long>(t.mega_min), static_cast<long long>(t.mega_max));
      }
      std::printf(
          "| %s | %lld | %lld | %s | %.3f | %.3f | %.3f | %.3f | %.3f | %.0f | %.0f | %.3f | %.3f | "
          "%.2f× | %.2f× | %.1f | %.1f | %.0f | %s | %zu%s |\n",
          spec.name.c_str(), static_cast<long long>(rig->mesh.num_triangles()),
          static_cast<long long>(t.intervals), name.c_str(), query_ms(t), t.ms_refit / n,
          (t.ms_classify + t.ms_merge) / n, t.ms_traverse / n, t.ms_elementary / n,
          t.bv_tests / n, t.pctp / n, t.bv_tests / b.bv_tests, t.pctp / b.pctp,
          query_ms(b) / query_ms(t), query_ms(k) / query_ms(t), t.h_minus / n,
          t.h_uncertain / n, t.atomic / n, mega, t.contacts, t.agrees ? "" : " MISMATCH");
      std::fflush(stdout);
    }
    }  // clips
  }
  return failures == 0 ? 0 : 1;
}

// --- Google Benchmark: one interval query per iteration, mid-clip -------------------------------

void bm_interval(benchmark::State& state, SceneSpec spec, std::string method_name) {
  static std::map<std::string, std::unique_ptr<RadialViewScene>> scenes;
  auto& scene = scenes[spec.model];
  if (!scene) {
    scene = std::make_unique<RadialViewScene>(load_rig(spec.model), std::max(0, spec.clip));
  }
  auto method = scene->method(method_name);
  const std::int32_t i = scene->motion->num_samples() / 2;
  skelcd::skinning::Positions x0, x1;
  scene->welded(i, x0);
  scene->welded(i + 1, x1);
  scene->poses->select_samples(i, i + 1);
  skelcd::culling::FrameResult out;
  double refit_us = 0;
  for (auto _ : state) {
    out.clear();
    method->detect_ccd(x0, x1, out);
    refit_us += out.times.refit_us;
  }
  state.counters["refit_ms"] =
      benchmark::Counter(refit_us / 1000, benchmark::Counter::kAvgIterations);
  state.counters["BVOT"] = static_cast<double>(out.counters.bv_tests);
  state.counters["PCTP"] = static_cast<double>(out.counters.candidate_pairs);
  state.SetLabel(spec.name + "/" + method_name);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<SceneSpec> scenes = all_scenes();
  std::int32_t intervals = 0;
  std::int32_t first = 0;
  bool google = false;
  std::vector<char*> rest = {argv[0]};
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg.rfind("--scenes=", 0) == 0) {
      std::vector<SceneSpec> picked;
      std::string list = arg.substr(9) + ",";
      for (std::size_t p = 0, q; (q = list.find(',', p)) != std::string::npos; p = q + 1) {
        const std::string name = list.substr(p, q - p);
        for (const auto& s : all_scenes()) {
          if (s.name == name) picked.push_back(s);
        }
      }
      scenes = picked;
    } else if (arg.rfind("--model=", 0) == 0) {
      // An ad-hoc scene: a gen: spec or a model path (first clip).
      scenes = {SceneSpec{arg.substr(8), arg.substr(8), -1}};
    } else if (arg.rfind("--intervals=", 0) == 0) {
      intervals = std::stoi(arg.substr(12));
    } else if (arg.rfind("--first=", 0) == 0) {
      first = std::max(0, std::stoi(arg.substr(8)));
    } else if (arg == "--dcd") {
      // Time one DCD per method at sample 0 of each scene (the precondition pass's cost).
      for (const auto& spec : scenes) {
        RadialViewScene scene(load_rig(spec.model), std::max(0, spec.clip));
        skelcd::skinning::Positions x;
        scene.welded(0, x);
        for (const char* m : {"bvh", "dynamic"}) {
          auto method = scene.method(m);
          skelcd::culling::FrameResult out;
          const auto start = std::chrono::steady_clock::now();
          method->detect_dcd(x, out);
          std::printf("%s %s DCD: %.1f ms, %lld candidate pairs, %lld tt tests, %lld pairs\n",
                      spec.name.c_str(), m,
                      std::chrono::duration<double, std::milli>(
                          std::chrono::steady_clock::now() - start).count(),
                      static_cast<long long>(out.counters.candidate_pairs),
                      static_cast<long long>(out.counters.tt_tests),
                      static_cast<long long>(out.counters.dcd_pairs));
        }
      }
      return 0;
    } else if (arg == "--benchmark") {
      google = true;
    } else {
      rest.push_back(argv[a]);
    }
  }
  if (!google) return run_table(scenes, first, intervals);
  for (const auto& s : scenes) {
    for (const char* m : {"bvh", "kdop", "rvbc", "dynamic"}) {
      benchmark::RegisterBenchmark((s.name + "/" + m).c_str(), bm_interval, s, std::string(m))
          ->Unit(benchmark::kMillisecond);
    }
  }
  int n = static_cast<int>(rest.size());
  benchmark::Initialize(&n, rest.data());
  benchmark::AddCustomContext("build", SKELCD_BUILD_TYPE);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
