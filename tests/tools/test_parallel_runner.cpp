// The runner with several threads: the same rows, in the same order, as a serial run (every
// counter, contact and DCD pair; only the timings differ), on a real character and a generated
// rig, for bvh, dynamic and auto; rows handed over one at a time and in order; a bounded number of
// rows waiting to be reported; an error reported after exactly the rows a serial run reports; and
// the methods that carry state between queries kept serial — with a run that shows why.

#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/task_scheduler_observer.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "clustering/bone_poses.hpp"
#include "culling/feature_topology.hpp"
#include "culling/hierarchy_cache.hpp"
#include "culling/method_registry.hpp"
#include "culling/routed_method.hpp"
#include "segmentation/segmentation.hpp"
#include "skinning/errors.hpp"
#include "skinning/load.hpp"
#include "skinning/rig_motion.hpp"
#include "skinning/topology.hpp"
#include "tests/support/test_support.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/runner.hpp"

namespace {

using namespace skelcd;
using namespace skelcd::tools;
using skinning::Positions;

const std::string kCharacter = test::assimp_model("X/BCN_Epileptic.X").string();

std::vector<FrameReport> collect(ClipRunner& runner) {
  std::vector<FrameReport> reports;
  runner.run([&](const FrameReport& r) { reports.push_back(r); });
  return reports;
}

void expect_same_counters(const culling::Counters& a, const culling::Counters& b,
                          const std::string& where) {
#define SKELCD_SAME(field) EXPECT_EQ(a.field, b.field) << where << ": " #field
  SKELCD_SAME(atomic_clusters);
  SKELCD_SAME(mega_clusters);
  SKELCD_SAME(h_minus);
  SKELCD_SAME(h_uncertain);
  SKELCD_SAME(bv_tests);
  SKELCD_SAME(candidate_pairs);
  SKELCD_SAME(vf_tests);
  SKELCD_SAME(ee_tests);
  SKELCD_SAME(vf_contacts);
  SKELCD_SAME(ee_contacts);
  SKELCD_SAME(tt_tests);
  SKELCD_SAME(dcd_pairs);
  SKELCD_SAME(feature_bv_tests);
#undef SKELCD_SAME
}

/// Every row equal except its times; returns the number of contacts + DCD pairs seen.
std::size_t expect_same_rows(const std::vector<FrameReport>& serial,
                             const std::vector<FrameReport>& parallel) {
  EXPECT_EQ(serial.size(), parallel.size());
  std::size_t findings = 0;
  for (std::size_t i = 0; i < std::min(serial.size(), parallel.size()); ++i) {
    const auto& s = serial[i];
    const auto& p = parallel[i];
    const std::string where = "row " + std::to_string(i);
    EXPECT_EQ(s.row.sample, p.row.sample) << where;
    EXPECT_EQ(s.row.kind, p.row.kind) << where;
    EXPECT_EQ(s.row.t0, p.row.t0) << where;
    EXPECT_EQ(s.row.t1, p.row.t1) << where;
    expect_same_counters(s.row.counters, p.row.counters, where);
    EXPECT_EQ(s.contacts, p.contacts) << where;  // same order too
    EXPECT_EQ(s.dcd_pairs, p.dcd_pairs) << where;
    findings += s.contacts.size() + s.dcd_pairs.size();
  }
  return findings;
}

struct Loaded {
  skinning::LoadedModel model;
  std::unique_ptr<skinning::Motion> motion;
};

Loaded load(const std::string& spec) {
  Loaded l{skinning::load_model(spec), nullptr};
  l.motion = l.model.motion();
  return l;
}

/// The rows of a runner of `options` (radial view set up) handed a FeatureTopology of the mesh
/// that the caller does not keep; `freed`: whether it was gone once the runner was built.
std::vector<FrameReport> run_with_given_features(const Loaded& l, RunOptions options, bool& freed) {
  (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
  skinning::Topology topology = skinning::build_topology(l.motion->mesh());
  auto features = std::make_shared<const culling::FeatureTopology>(l.motion->mesh(), topology);
  const std::weak_ptr<const culling::FeatureTopology> given = features;
  ClipRunner runner(*l.motion, options, std::move(topology), {}, std::move(features));
  freed = given.expired();
  return collect(runner);
}

/// Runs `method` over `frames` serially and with `threads` workers in blocks of `block` samples.
std::pair<std::vector<FrameReport>, std::vector<FrameReport>> serial_and_parallel(
    const Loaded& l, const std::string& method, const std::string& frames, std::int32_t threads,
    std::int32_t block, QuerySet query = QuerySet::both, RunPlan* parallel_plan = nullptr) {
  std::vector<FrameReport> out[2];
  for (const int k : {0, 1}) {
    RunOptions options;
    options.method = method;
    options.frames = parse_frame_range(frames);
    options.query = query;
    options.threads = k == 0 ? 1 : threads;
    options.block_samples = block;
    (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    ClipRunner runner(*l.motion, options);
    if (k == 1) {
      EXPECT_EQ(runner.plan().threads, threads) << method << ": " << runner.plan().serial_reason;
      if (parallel_plan != nullptr) *parallel_plan = runner.plan();
    } else {
      EXPECT_EQ(runner.plan().threads, 1);
    }
    out[k] = collect(runner);
  }
  return {std::move(out[0]), std::move(out[1])};
}

// The threads of this process now (its entries in /proc/self/task).
std::size_t threads_of_this_process() {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator("/proc/self/task"))
    ++n;
  return n;
}

TEST(ParallelRunner, WarmingUpTheWorkersStartsThemForAParallelRunOnly) {
  // Nothing for a serial run, nor for a count the runner refuses (it reports that itself).
  const std::size_t before = threads_of_this_process();
  warm_up_workers(1);
  warm_up_workers(-2);
  EXPECT_EQ(threads_of_this_process(), before);
  // Two threads: oneTBB's worker is up when it returns (this test's process had none, unless
  // an earlier test in the same process started them).
  warm_up_workers(2);
  EXPECT_GE(threads_of_this_process(), std::max<std::size_t>(before, 2));
}

// A real clip that holds one pose: Debian's MDL (HL1)/unnamed_bones.mdl, 76 samples of one pose
// with 1,852 contacts an interval (eight stacked slabs within float noise of each other). With
// RunOptions::reuse_static_intervals most CCD rows are handed on (no stage time) and every row
// equals the queried one. `dynamic` with `--query ccd` carries the intersecting pairs at each
// interval's end into the next, a function of that pose: it hands rows on too, but never the row
// of an interval whose start it found by a DCD of its own (its counters hold that DCD's), and
// with `--accuracy fast` (whose carried pairs may miss one) it is queried every time.
TEST(RunnerStatic, UnnamedBonesRowsAreTheQueriedOnes) {
  const auto l = load(test::assimp_model("MDL/MDL (HL1)/unnamed_bones.mdl").string());
  const auto run = [&](const char* method,
                       QuerySet query,
                       bool reuse,
                       const char* frames = "0:12",
                       ccd::Accuracy accuracy = ccd::Accuracy::conservative) {
    RunOptions options;
    options.method = method;
    options.frames = parse_frame_range(frames);
    options.query = query;
    options.accuracy = accuracy;
    options.reuse_static_intervals = reuse;
    (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    ClipRunner runner(*l.motion, options);
    return collect(runner);
  };
  // CCD rows queried (their stages took time) and handed on (none did).
  const auto count = [](const std::vector<FrameReport>& rows,
                        int& queried,
                        int& handed_on,
                        bool all_contacts = true) {
    queried = handed_on = 0;
    for (const auto& r : rows) {
      if (r.row.kind != QueryKind::ccd) continue;
      if (all_contacts) {
        EXPECT_EQ(r.row.counters.vf_contacts + r.row.counters.ee_contacts, 1852);
      }
      (r.row.times.elementary_us > 0.0 ? queried : handed_on) += 1;
    }
  };
  for (const char* method : {"bvh", "kdop", "dynamic"}) {
    SCOPED_TRACE(method);
    const std::vector<FrameReport> each = run(method, QuerySet::both, false);
    const std::vector<FrameReport> held = run(method, QuerySet::both, true);
    EXPECT_GE(expect_same_rows(each, held), 12u * 1852);
    int queried = 0;
    int handed_on = 0;
    count(each, queried, handed_on);
    EXPECT_EQ(queried, 12);
    // Held bit for bit at both ends on most intervals (a few samples differ from the others in
    // their last bits — the keys' interpolation — and are queried).
    count(held, queried, handed_on);
    EXPECT_EQ(queried + handed_on, 12);
    EXPECT_GE(handed_on, 6);
  }
  // Samples 0-3 differ in their last bits, so the first held interval (3 -> 4) follows one that
  // ended at its pose; from sample 3 on, the first held interval is the run's first and its
  // start takes a DCD of the method's own.
  for (const char* frames : {"0:12", "3:15"}) {
    SCOPED_TRACE(frames);
    for (const char* method : {"dynamic", "auto"}) {
      SCOPED_TRACE(method);
      const std::vector<FrameReport> each = run(method, QuerySet::ccd, false, frames);
      const std::vector<FrameReport> held = run(method, QuerySet::ccd, true, frames);
      EXPECT_GE(expect_same_rows(each, held), 12u * 1852);
      int queried = 0;
      int handed_on = 0;
      count(held, queried, handed_on);
      EXPECT_EQ(queried + handed_on, 12);
      EXPECT_GE(handed_on, 6);
    }
  }
  // The run's first interval held at 3 -> 4 is queried, and so is the next one (the first whose
  // row a later query would give); every other is handed on.
  {
    const std::vector<FrameReport> held = run("dynamic", QuerySet::ccd, true, "3:15");
    ASSERT_EQ(held.size(), 12u);
    EXPECT_GT(held[0].row.times.elementary_us, 0.0);
    EXPECT_GT(held[1].row.times.elementary_us, 0.0);
    EXPECT_GT(held[0].row.counters.tt_tests, held[1].row.counters.tt_tests);
    for (std::size_t i = 2; i < held.size(); ++i) {
      EXPECT_EQ(held[i].row.times.elementary_us, 0.0) << i;
    }
  }
  int queried = 0;
  int handed_on = 0;
  count(
      run("dynamic", QuerySet::ccd, true, "0:12", ccd::Accuracy::fast), queried, handed_on, false);
  EXPECT_EQ(queried, 12) << "with fast tests, what it carries may not follow from the pose";
}

TEST(ParallelRunner, RowsTheCallbackTakesEqualRowsItCopiesSerialAndParallel) {
  const auto l = load(kCharacter);
  for (const std::int32_t threads : {1, 2}) {
    SCOPED_TRACE(threads);
    std::vector<FrameReport> rows[2];
    for (const bool take : {false, true}) {
      RunOptions options;
      options.method = "bvh";
      options.frames = parse_frame_range("36:41");
      options.threads = threads;
      options.block_samples = 2;
      ClipRunner runner(*l.motion, options);
      ASSERT_EQ(runner.plan().threads, threads);
      runner.run([&](FrameReport& r) {
        if (take) {
          rows[1].push_back(std::move(r));
        } else {
          rows[0].push_back(r);
        }
      });
    }
    EXPECT_EQ(rows[0].size(), 6u + 5u);
    EXPECT_GT(expect_same_rows(rows[0], rows[1]), 0u) << "no findings: the clip proves nothing";
  }
}

TEST(ParallelRunner, RealCharacterRowsEqualSerialForBvhDynamicAndAuto) {
  const auto l = load(kCharacter);
  for (const char* method : {"bvh", "dynamic", "auto"}) {
    SCOPED_TRACE(method);
    // Blocks of 2 samples over 4 workers: every block boundary is a worker change.
    const auto [serial, parallel] = serial_and_parallel(l, method, "36:47", 4, 2);
    EXPECT_EQ(serial.size(), 12u + 11u);
    EXPECT_GT(expect_same_rows(serial, parallel), 0u) << "no findings: the clip proves nothing";
  }
}

/// Builds a `bvh` whose hierarchy comes through `cache` (what a parallel check's baseline does).
void bvh_through(
    const std::shared_ptr<culling::HierarchyCache>& cache,
    const skinning::Mesh& mesh,
    const skinning::Topology& topology) {
  culling::MethodOptions options;
  options.hierarchies = cache;
  (void)culling::make_method("bvh", mesh, topology, options);
}

TEST(ParallelRunner, WorkersShareOneBuildOfEachHierarchyAndTheCacheIsClosedAfter) {
  // bvh, and auto (which sends BCN_Epileptic whole to `bvh`): four workers' methods, one build
  // of their hierarchy, shared with what the caller built through the same cache first (a
  // parallel check's baseline `bvh`); closed when the runner is built. The rows are the serial
  // run's (RealCharacterRowsEqualSerialForBvhDynamicAndAuto).
  const auto l = load(kCharacter);
  for (const char* method : {"bvh", "auto"}) {
    SCOPED_TRACE(method);
    RunOptions options;
    options.method = method;
    options.frames = parse_frame_range("0:20");
    options.threads = 4;
    options.block_samples = 2;
    auto topology = skinning::build_topology(l.motion->mesh());
    auto cache = std::make_shared<culling::HierarchyCache>();
    bvh_through(cache, l.motion->mesh(), topology);
    ASSERT_EQ(cache->builds(), 2u);  // its tree and its fan sieve's slot adjacency
    ClipRunner runner(*l.motion, options, std::move(topology), {}, {}, cache);
    ASSERT_EQ(runner.plan().threads, 4) << runner.plan().serial_reason;
    // The tree copied four times; one slot adjacency for the workers, who share the runner's
    // FeatureTopology (the caller's `bvh` built one of its own), built once and shared by three.
    EXPECT_EQ(cache->builds(), 3u);
    EXPECT_EQ(cache->reuses(), 4u + 3u);
    // Closed: what it built is freed and later calls keep nothing.
    bvh_through(cache, l.motion->mesh(), runner.topology());
    EXPECT_EQ(cache->builds(), 3u);
    EXPECT_EQ(cache->reuses(), 7u);
  }
  // A run that turns out serial closes the caller's cache without using it.
  RunOptions serial;
  serial.method = "bvh";
  serial.frames = parse_frame_range("0:3");
  serial.threads = 1;
  auto cache = std::make_shared<culling::HierarchyCache>();
  ClipRunner runner(*l.motion, serial, skinning::build_topology(l.motion->mesh()), {}, {}, cache);
  EXPECT_EQ(cache->builds(), 0u);
  bvh_through(cache, l.motion->mesh(), runner.topology());
  EXPECT_EQ(cache->builds(), 0u);
}

TEST(ParallelRunner, ASerialRunIsLentTheBaselinesTreeThroughAHandOverCache) {
  // A serial check: its baseline `bvh` builds the whole mesh's tree through a hand-over cache and
  // is freed; the runner's one method — `bvh`, or `dynamic` for its DCD tree (the run has DCD
  // queries) — is lent that tree, refit at the baseline's pose, instead of building its own.
  // `kdop` (a 16-DOP tree) builds its own. The rows are those of a run without the cache.
  const auto l = load(test::asset("characters/CesiumMan.glb").string());
  for (const char* method : {"bvh", "dynamic", "kdop"}) {
    SCOPED_TRACE(method);
    RunOptions options;
    options.method = method;
    options.frames = parse_frame_range("0:12");
    options.threads = 1;
    (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    ClipRunner alone(*l.motion, options, skinning::build_topology(l.motion->mesh()));
    const auto rows = collect(alone);

    auto cache =
        std::make_shared<culling::HierarchyCache>(culling::HierarchyCache::Sharing::hand_over);
    auto topology = skinning::build_topology(l.motion->mesh());
    bvh_through(cache, l.motion->mesh(), topology);
    ASSERT_EQ(cache->builds(), 1u);  // its tree (no slot adjacency: objects are not kept)
    ClipRunner runner(*l.motion, options, std::move(topology), {}, {}, cache);
    const bool lent = std::string(method) != "kdop";
    EXPECT_EQ(cache->reuses(), lent ? 1u : 0u);
    EXPECT_EQ(cache->builds(), 1u);  // the runner's method keeps what it builds to itself
    EXPECT_GT(expect_same_rows(rows, collect(runner)), 0u)
        << "no findings: the clip proves nothing";
    // Closed once the method is built: nothing held, nothing lent again.
    bvh_through(cache, l.motion->mesh(), runner.topology());
    EXPECT_EQ(cache->builds(), 1u);
    EXPECT_EQ(cache->reuses(), lent ? 1u : 0u);
  }
  // A parallel run given one does not lend through it (its workers would build one after
  // another): closed, and its workers share a cache of copies; the serial run's rows.
  RunOptions options;
  options.method = "bvh";
  options.frames = parse_frame_range("0:12");
  options.block_samples = 2;
  options.threads = 1;
  ClipRunner alone(*l.motion, options, skinning::build_topology(l.motion->mesh()));
  const auto rows = collect(alone);
  options.threads = 2;
  auto cache =
      std::make_shared<culling::HierarchyCache>(culling::HierarchyCache::Sharing::hand_over);
  auto topology = skinning::build_topology(l.motion->mesh());
  bvh_through(cache, l.motion->mesh(), topology);
  ClipRunner runner(*l.motion, options, std::move(topology), {}, {}, cache);
  ASSERT_EQ(runner.plan().threads, 2) << runner.plan().serial_reason;
  EXPECT_EQ(cache->builds(), 1u);
  EXPECT_EQ(cache->reuses(), 0u);
  expect_same_rows(rows, collect(runner));
}

TEST(ParallelRunner, DynamicsWorkersShareOneRimFirstFeatureTopology) {
  // `dynamic` on CesiumMan, which has no boundary loop to cap (ghost caps would give each
  // method a mesh of its own): four workers' methods, one build of their rim-first
  // FeatureTopology through the runner's cache, shared by the other three, and of their DCD
  // tree and its slot adjacency. Their rows are the serial run's
  // (RealCharacterRowsEqualSerialForBvhDynamicAndAuto, and here below).
  const auto l = load(test::asset("characters/CesiumMan.glb").string());
  RunOptions options;
  options.method = "dynamic";
  options.frames = parse_frame_range("0:12");
  options.block_samples = 2;
  (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
  std::vector<FrameReport> rows[2];
  for (const int k : {0, 1}) {
    options.threads = k == 0 ? 1 : 4;
    auto cache = std::make_shared<culling::HierarchyCache>();
    auto topology = skinning::build_topology(l.motion->mesh());
    // A parallel check's baseline `bvh` first: its tree and its slot adjacency.
    if (k == 1) bvh_through(cache, l.motion->mesh(), topology);
    ClipRunner runner(*l.motion, options, std::move(topology), {}, {}, cache);
    if (k == 1) {
      // The rim-first FeatureTopology, one build shared by the other three; the DCD trees (the
      // run has DCD queries: built with the methods), four copies of the baseline's tree (the
      // same key); their slot adjacency over the rim-first features, one build shared by three.
      ASSERT_EQ(runner.plan().threads, 4) << runner.plan().serial_reason;
      EXPECT_EQ(cache->builds(), 2u + 1u + 1u);
      EXPECT_EQ(cache->reuses(), 3u + 4u + 3u);
    } else {
      EXPECT_EQ(cache->builds(), 0u);  // one method: the cache closed unused
    }
    rows[k] = collect(runner);
  }
  EXPECT_GT(expect_same_rows(rows[0], rows[1]), 0u) << "no findings: the clip proves nothing";
}

TEST(ParallelRunner, ATopologyTheCallerKeepsReadingServesTheCallersFeatures) {
  // A parallel check's baseline thread reads the weld and builds the mesh's FeatureTopology while
  // the runner is built: given the same topology object, the runner and its workers' `bvh`s take
  // those features (they stay held once the caller lets go) and read that very topology; given
  // a copy of it, as before, they cannot take them (FeatureTopology::built_from) and build a
  // second FeatureTopology. The rows are the serial run's either way.
  const auto l = load(test::asset("characters/CesiumMan.glb").string());
  RunOptions options;
  options.method = "bvh";
  options.frames = parse_frame_range("0:20");
  options.block_samples = 6;
  std::vector<FrameReport> rows[3];
  for (const int k : {0, 1, 2}) {
    SCOPED_TRACE(k);
    options.threads = k == 0 ? 1 : 2;
    const auto topology =
        std::make_shared<const skinning::Topology>(skinning::build_topology(l.motion->mesh()));
    auto features = std::make_shared<const culling::FeatureTopology>(l.motion->mesh(), *topology);
    const std::weak_ptr<const culling::FeatureTopology> given = features;
    const bool copy = k == 2;
    const auto runner =
        copy
            ? std::make_unique<ClipRunner>(
                  *l.motion, options, skinning::Topology(*topology), MethodFactory{}, features)
            : std::make_unique<ClipRunner>(*l.motion, options, topology, MethodFactory{}, features);
    features.reset();
    EXPECT_EQ(runner->plan().threads, k == 0 ? 1 : 2) << runner->plan().serial_reason;
    EXPECT_EQ(&runner->topology() == topology.get(), !copy);
    EXPECT_EQ(given.expired(), copy);  // `bvh` with incremental DCD holds the features it took
    rows[k] = collect(*runner);
  }
  EXPECT_GT(expect_same_rows(rows[0], rows[1]), 0u) << "no findings: the clip proves nothing";
  expect_same_rows(rows[0], rows[2]);
}

TEST(ParallelRunner, AutosRoutedMethodRowsEqualSerial) {
  // `auto` sends BCN_Epileptic whole to `bvh` (every part capped or small: RoutingOptions::
  // all_closed_method). Without that rule, and with the segmentation `dynamic` needs, its routed
  // method gives every part to `dynamic` (capped or small), which answers through `auto` — as
  // `auto` did before the rule took capped parts: in blocks of 2 samples over 4 workers, the
  // serial rows.
  const auto l = load(kCharacter);
  culling::RoutingOptions grouped;
  grouped.all_closed_method.clear();
  std::vector<FrameReport> out[2];
  std::set<std::string> methods;
  for (const int k : {0, 1}) {
    RunOptions options;
    options.method = "dynamic";  // so that setup_radial_view makes the segmentation
    options.frames = parse_frame_range("36:47");
    options.threads = k == 0 ? 1 : 4;
    options.block_samples = 2;
    options.factory_methods_stateless = true;
    (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    ClipRunner runner(
        *l.motion,
        options,
        [&grouped, &methods](
            const skinning::Mesh& mesh,
            const skinning::Topology& topology,
            const culling::MethodOptions& method_options) {
          auto m = culling::make_routed_method(mesh, topology, method_options, grouped);
          for (const auto& route : culling::routes_of(*m)) methods.insert(route.method);
          return m;
        });
    if (k == 1) {
      EXPECT_EQ(runner.plan().threads, 4) << runner.plan().serial_reason;
    }
    out[k] = collect(runner);
  }
  EXPECT_EQ(methods, (std::set<std::string>{"dynamic"}));
  EXPECT_GT(expect_same_rows(out[0], out[1]), 0u) << "no findings: the clip proves nothing";
}

// Incremental DCD (RunOptions::incremental_dcd, the default with both queries) against full DCD at
// every sample: the same contacts and DCD pairs in every row, far fewer triangle tests, and each
// block (serial or parallel) starting with a full DCD.
TEST(ParallelRunner, DynamicsFeaturesServeTheDcdUpdatersAndTheRunnersAreFreed) {
  // `dynamic` works on features of its own owner order (rims first) and does not take the
  // runner's; the runner's incremental-DCD updaters read no ownership and take the method's, so
  // the runner's own is freed. `bvh` takes the runner's, which stays. The DCD rows (from the
  // updaters over the rim-first features) are `bvh`'s, serial and on two threads.
  const auto l = load(test::asset("characters/CesiumMan.glb").string());
  std::vector<FrameReport> rows[2][2];  // [method][threads − 1]
  const char* methods[2] = {"bvh", "dynamic"};
  for (const int m : {0, 1}) {
    for (const int threads : {1, 2}) {
      SCOPED_TRACE(std::string(methods[m]) + " on " + std::to_string(threads));
      RunOptions options;
      options.method = methods[m];
      options.frames = parse_frame_range("0:20");
      options.threads = threads;
      options.block_samples = 6;
      bool freed = false;
      rows[m][threads - 1] = run_with_given_features(l, options, freed);
      EXPECT_EQ(freed, m == 1);
    }
  }
  for (const int threads : {0, 1}) {
    const auto& bvh = rows[0][threads];
    const auto& dynamic = rows[1][threads];
    ASSERT_EQ(bvh.size(), dynamic.size());
    std::size_t pairs = 0;
    for (std::size_t i = 0; i < bvh.size(); ++i) {
      EXPECT_EQ(bvh[i].dcd_pairs, dynamic[i].dcd_pairs) << "row " << i;
      EXPECT_EQ(bvh[i].contacts, dynamic[i].contacts) << "row " << i;
      pairs += bvh[i].dcd_pairs.size();
    }
    EXPECT_GT(pairs, 0u) << "CesiumMan's walk intersects itself: the rows must hold pairs";
  }
}

TEST(ParallelRunner, WithoutIncrementalDcdTheRunnerHoldsNoFeaturesOfItsOwn) {
  // Only the incremental-DCD updaters read the runner's features once the methods are built.
  // BCN_Epileptic is open: `dynamic` caps it with ghost triangles, and its features describe the
  // capped mesh, so it does not take the runner's and they cannot serve the updaters either. A
  // CCD-only run frees them; a run with both queries keeps them for its updaters.
  const auto l = load(kCharacter);
  for (const QuerySet query : {QuerySet::ccd, QuerySet::both}) {
    for (const int threads : {1, 2}) {
      SCOPED_TRACE(std::to_string(static_cast<int>(query)) + " on " + std::to_string(threads));
      RunOptions options;
      options.method = "dynamic";
      options.query = query;
      options.frames = parse_frame_range("0:6");
      options.threads = threads;
      options.block_samples = 3;
      bool freed = false;
      EXPECT_FALSE(run_with_given_features(l, options, freed).empty());
      EXPECT_EQ(freed, query == QuerySet::ccd);
    }
  }
}

TEST(ParallelRunner, IncrementalDcdRowsHoldTheFullDcdsPairsWithFewerTests) {
  const auto l = load(kCharacter);
  for (const char* method : {"bvh", "auto"}) {
    SCOPED_TRACE(method);
    std::vector<FrameReport> rows[2];
    for (const int incremental : {0, 1}) {
      RunOptions options;
      options.method = method;
      options.frames = parse_frame_range("30:55");
      options.threads = 2;
      options.block_samples = 8;
      options.incremental_dcd = incremental != 0;
      (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
      ClipRunner runner(*l.motion, options);
      rows[incremental] = collect(runner);
    }
    ASSERT_EQ(rows[0].size(), rows[1].size());
    std::int64_t full_tests = 0, incremental_tests = 0;
    std::size_t dcd_pairs = 0;
    bool changes = false;
    bool have_previous = false;
    std::vector<DcdPairRow> previous;
    for (std::size_t i = 0; i < rows[0].size(); ++i) {
      const auto& full = rows[0][i];
      const auto& inc = rows[1][i];
      const std::string where = "row " + std::to_string(i);
      EXPECT_EQ(full.contacts, inc.contacts) << where;
      EXPECT_EQ(full.dcd_pairs, inc.dcd_pairs) << where;
      if (full.row.kind != QueryKind::dcd) continue;
      EXPECT_EQ(full.row.counters.dcd_pairs, inc.row.counters.dcd_pairs) << where;
      full_tests += full.row.counters.tt_tests;
      incremental_tests += inc.row.counters.tt_tests;
      dcd_pairs += full.dcd_pairs.size();
      // A block's first sample is a full DCD: the same counters as the full run's row.
      if ((full.row.sample - 30) % 8 == 0) {
        EXPECT_EQ(full.row.counters.candidate_pairs, inc.row.counters.candidate_pairs) << where;
      }
      std::vector<DcdPairRow> now = full.dcd_pairs;
      for (auto& p : now) p.frame = 0;
      if (have_previous && now != previous) changes = true;
      previous = std::move(now);
      have_previous = true;
    }
    EXPECT_GT(dcd_pairs, 0u) << "no DCD pairs: the clip proves nothing";
    EXPECT_TRUE(changes) << "the pairs must change over the clip";
    EXPECT_LT(incremental_tests * 3, full_tests) << "the update must test far fewer pairs";
  }
}

// Without --block-samples the blocks hold B = clamp(samples / 8, 4, 64) samples while more than
// 4·B are left, then a quarter of what is left (at least 2), so that the last blocks a pipeline
// hands out are small and the workers run out of work together: read from the rows, where a
// block's first DCD is a full one (the full run's counters) and the others are updates.
TEST(ParallelRunner, DefaultBlocksShrinkTowardsTheEndOfTheClip) {
  for (const int frames : {100, 45}) {
    SCOPED_TRACE(frames);
    const auto l = load("gen:rope?triangles=200&frames=" + std::to_string(frames));
    std::vector<FrameReport> rows[2];
    RunPlan plan;
    for (const int incremental : {0, 1}) {
      RunOptions options;
      options.method = "bvh";
      options.threads = 2;
      options.incremental_dcd = incremental != 0;
      ClipRunner runner(*l.motion, options);
      plan = runner.plan();
      rows[incremental] = collect(runner);
    }
    ASSERT_EQ(rows[0].size(), rows[1].size());
    std::vector<std::int32_t> starts;
    for (std::size_t i = 0; i < rows[0].size(); ++i) {
      const auto& full = rows[0][i].row;
      const auto& inc = rows[1][i].row;
      if (full.kind != QueryKind::dcd) continue;
      if (full.counters.candidate_pairs == inc.counters.candidate_pairs &&
          full.counters.tt_tests == inc.counters.tt_tests) {
        starts.push_back(full.sample);
      }
    }
    ASSERT_FALSE(starts.empty());
    EXPECT_EQ(starts.front(), 0);
    starts.push_back(frames);  // one past the last block
    std::vector<std::int32_t> sizes;
    for (std::size_t b = 0; b + 1 < starts.size(); ++b) sizes.push_back(starts[b + 1] - starts[b]);
    const std::int32_t largest = std::clamp(frames / 8, 4, 64);
    std::int32_t left = frames;
    for (std::size_t b = 0; b < sizes.size(); ++b) {
      SCOPED_TRACE(b);
      const bool last = b + 1 == sizes.size();
      if (left > 4 * largest) {
        EXPECT_EQ(sizes[b], largest);
      } else if (!last) {
        EXPECT_EQ(sizes[b], std::max((left + 3) / 4, 2)) << "a quarter of " << left;
      } else {
        EXPECT_GE(sizes[b], 2);  // the remainder below 2 joins the last block
        EXPECT_LE(sizes[b], 3);
      }
      left -= sizes[b];
    }
    EXPECT_LE(sizes.back(), largest / 2);
    EXPECT_EQ(plan.blocks, static_cast<std::int32_t>(sizes.size()));
    EXPECT_EQ(plan.block_samples, largest);
    EXPECT_EQ(plan.threads, 2);
  }
}

// The rope (a closed tube) coils into itself from sample 17 of 24.
const std::string kRope = "gen:rope?triangles=200&frames=24";

TEST(ParallelRunner, GeneratedRigRowsEqualSerialForBvhAndDynamic) {
  const auto l = load(kRope);
  for (const char* method : {"bvh", "dynamic", "kdop"}) {
    SCOPED_TRACE(method);
    const auto [serial, parallel] = serial_and_parallel(l, method, "12:", 3, 3);
    EXPECT_EQ(serial.size(), 12u + 11u);
    EXPECT_GT(expect_same_rows(serial, parallel), 0u);
  }
  // The query subsets cut into blocks the same way.
  for (const auto query : {QuerySet::dcd, QuerySet::ccd}) {
    const auto [serial, parallel] = serial_and_parallel(l, "bvh", "12:", 2, 5, query);
    EXPECT_EQ(serial.size(), query == QuerySet::dcd ? 12u : 11u);
    EXPECT_GT(expect_same_rows(serial, parallel), 0u);
  }
}

/// Sample i: the first sample of `base` translated by (1000 i, 0, 0); one NaN at `nan_sample`.
class ShiftMotion : public skinning::Motion {
 public:
  ShiftMotion(const skinning::Motion& base, int samples) : base_(base), samples_(samples) {}
  const skinning::Mesh& mesh() const override { return base_.mesh(); }
  int num_samples() const override { return samples_; }
  double sample_time(int i) const override { return 0.25 * i; }
  std::string name() const override { return "shift-clip"; }
  void positions(int i, Positions& out) const override {
    base_.positions(0, out);
    out.col(0).array() += 1000.0 * i;
    if (i == nan_sample) out(4, 1) = std::numeric_limits<double>::quiet_NaN();
  }
  int nan_sample = -1;

 private:
  const skinning::Motion& base_;
  int samples_;
};

/// A stateless method that tells which sample it was given (from the shift) and can stall.
class ProbeMethod : public culling::CullingMethod {
 public:
  using Hook = std::function<void(int sample)>;
  explicit ProbeMethod(Hook hook) : hook_(std::move(hook)) {}
  std::string_view name() const override { return "probe"; }
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    const skinning::Positions& x = at.x;
    hook_(sample_of(x));
    out.counters.tt_tests = sample_of(x);
  }
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    const skinning::Positions& x_t0 = interval.x_t0;
    const skinning::Positions& x_t1 = interval.x_t1;
    hook_(sample_of(x_t0));
    out.counters.vf_tests = 1000 * sample_of(x_t0) + sample_of(x_t1);
  }

 private:
  static int sample_of(const Positions& x) {
    return static_cast<int>(std::lround(x(0, 0) / 1000.0));
  }
  Hook hook_;
};

TEST(ParallelRunner, RowsArriveOneAtATimeInOrderWithABoundedBacklog) {
  const auto l = load("gen:rope?triangles=200&frames=2");
  ShiftMotion motion(*l.motion, 200);
  std::atomic<int> started{0};
  std::atomic<int> max_backlog{0};
  std::atomic<int> emitted{0};
  RunOptions options;
  options.threads = 4;
  options.block_samples = 2;
  options.factory_methods_stateless = true;
  ClipRunner runner(motion, options, [&](const skinning::Mesh&, const skinning::Topology&,
                                         const culling::MethodOptions&) {
    return std::make_unique<ProbeMethod>([&](int sample) {
      // The first block stalls: the others may run ahead only as far as the live blocks allow.
      if (sample == 0) std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const int backlog = ++started - emitted.load();
      int seen = max_backlog.load();
      while (backlog > seen && !max_backlog.compare_exchange_weak(seen, backlog)) {
      }
    });
  });
  ASSERT_EQ(runner.plan().threads, 4);
  std::atomic<bool> inside{false};
  std::vector<FrameReport> reports;
  runner.run([&](const FrameReport& r) {
    EXPECT_FALSE(inside.exchange(true)) << "two rows reported at once";
    reports.push_back(r);
    ++emitted;
    inside = false;
  });
  ASSERT_EQ(reports.size(), 200u + 199u);
  for (std::size_t i = 0; i < reports.size(); ++i) {
    const auto sample = static_cast<int>(i / 2);
    ASSERT_EQ(reports[i].row.sample, sample) << i;
    ASSERT_EQ(reports[i].row.kind, i % 2 == 0 ? QueryKind::dcd : QueryKind::ccd) << i;
    if (i % 2 == 0) {
      EXPECT_EQ(reports[i].row.counters.tt_tests, sample);
    } else {
      EXPECT_EQ(reports[i].row.counters.vf_tests, 1000 * sample + sample + 1);
    }
  }
  // 2 × threads live blocks of at most 4 rows each (2 samples: DCD + CCD).
  EXPECT_LE(max_backlog.load(), 2 * 4 * 4);
  EXPECT_GE(max_backlog.load(), 4) << "the workers never ran ahead of the stalled block";
}

TEST(ParallelRunner, AnErrorComesAfterExactlyTheRowsASerialRunReports) {
  const auto l = load("gen:rope?triangles=200&frames=2");
  for (const int threads : {1, 4}) {
    ShiftMotion motion(*l.motion, 40);
    motion.nan_sample = 17;
    RunOptions options;
    options.threads = threads;
    options.block_samples = 3;
    options.factory_methods_stateless = true;
    ClipRunner runner(motion, options, [](const skinning::Mesh&, const skinning::Topology&,
                                          const culling::MethodOptions&) {
      return std::make_unique<ProbeMethod>([](int) {});
    });
    EXPECT_EQ(runner.plan().threads, threads);
    std::vector<FrameReport> reports;
    EXPECT_THROW_MESSAGE(runner.run([&](const FrameReport& r) { reports.push_back(r); }),
                         InvalidInput, "shift-clip: sample 17 (t = 4.25");
    EXPECT_EQ(reports.size(), 2u * 16u + 1u) << threads;  // dcd 0 … dcd 16, ccd 0 … ccd 15
  }
}

TEST(ParallelRunner, AMethodThatCannotBeBuiltStopsTheRunnerWithItsError) {
  // The workers' methods are built together by oneTBB's threads: a failure on any of them, or on
  // every one, reaches the caller as that error (none is lost, nothing outlives the constructor;
  // builds not yet started when one fails are cancelled).
  const auto l = load("gen:rope?triangles=200&frames=2");
  ShiftMotion motion(*l.motion, 20);
  for (const int failing_call : {0, 1, 2, 3, -1}) {  // -1: every call
    std::atomic<int> calls{0};
    RunOptions options;
    options.threads = 4;
    options.block_samples = 3;
    options.factory_methods_stateless = true;
    const auto factory =
        [&](const skinning::Mesh&,
            const skinning::Topology&,
            const culling::MethodOptions&) -> std::unique_ptr<culling::CullingMethod> {
      const int call = calls++;
      if (failing_call < 0 || call == failing_call) {
        throw InvalidInput("probe method " + std::to_string(call) + " refused");
      }
      return std::make_unique<ProbeMethod>([](int) {});
    };
    EXPECT_THROW_MESSAGE(ClipRunner(motion, options, factory), InvalidInput, "refused");
    EXPECT_LE(calls.load(), 4) << failing_call;  // one build per worker at most
  }
}

TEST(ParallelRunner, ThreadsResolveAndStatefulRunsStaySerial) {
  EXPECT_EQ(resolve_threads(0), std::max(1, tbb::info::default_concurrency()));
  EXPECT_EQ(resolve_threads(3), 3);
  EXPECT_THROW_MESSAGE((void)resolve_threads(-1), InvalidInput, "--threads -1");

  // The registry is the one source of why a method runs serially (MethodInfo::serial_reason),
  // given its options and whether a DCD precedes every CCD interval (not under --query ccd).
  const auto serial_reason = [](std::string_view name, const culling::MethodOptions& o, bool dcd) {
    const culling::MethodInfo* m = culling::find_method(name);
    EXPECT_NE(m, nullptr) << name;
    return m != nullptr && m->serial_reason ? m->serial_reason(o, dcd) : std::string();
  };
  culling::MethodOptions o;
  EXPECT_EQ(serial_reason("bvh", o, true), "");
  EXPECT_EQ(serial_reason("dynamic", o, true), "");
  EXPECT_NE(serial_reason("dynamic", o, false).find("--query ccd"), std::string::npos);
  EXPECT_NE(serial_reason("rvbc", o, false).find("--query ccd"), std::string::npos);
  EXPECT_EQ(serial_reason("bvh", o, false), "");
  o.accuracy = ccd::Accuracy::fast;
  EXPECT_NE(serial_reason("dynamic", o, true).find("--accuracy fast"), std::string::npos);
  o.min_separation = 0.01;  // nothing is skipped: the carried state is unused
  EXPECT_EQ(serial_reason("dynamic", o, true), "");
  EXPECT_EQ(culling::find_method("someone-elses"), nullptr);

  // Through the runner: a custom factory's methods are serial unless declared stateless, and
  // dynamic on --query ccd is serial with the reason in the plan.
  const auto l = load(kRope);
  RunOptions custom;
  custom.threads = 4;
  ClipRunner probe(*l.motion, custom, [](const skinning::Mesh&, const skinning::Topology&,
                                         const culling::MethodOptions&) {
    return std::make_unique<ProbeMethod>([](int) {});
  });
  EXPECT_EQ(probe.plan().threads, 1);
  EXPECT_NE(probe.plan().serial_reason.find("factory"), std::string::npos);
  RunOptions ccd_only;
  ccd_only.threads = 4;
  ccd_only.method = "dynamic";
  ccd_only.query = QuerySet::ccd;
  (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, ccd_only);
  ClipRunner dynamic(*l.motion, ccd_only);
  EXPECT_EQ(dynamic.plan().threads, 1);
  EXPECT_NE(dynamic.plan().serial_reason.find("--query ccd"), std::string::npos);
}

/// A method that takes 10 ms more per query than the one it wraps.
class SlowMethod final : public culling::CullingMethod {
 public:
  explicit SlowMethod(std::unique_ptr<culling::CullingMethod> inner) : inner_(std::move(inner)) {}
  [[nodiscard]] std::string_view name() const override { return inner_->name(); }

 protected:
  void dcd(const culling::Instant& at, culling::FrameResult& out) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    inner_->detect_dcd(at, out);
  }
  void ccd(const culling::Interval& interval, culling::FrameResult& out) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    inner_->detect_ccd(interval, out);
  }

 private:
  std::unique_ptr<culling::CullingMethod> inner_;
};

/// Why dynamic with --query ccd stays serial: forced into blocks anyway (a factory declared
/// stateless), each block's first interval starts without the state the previous interval left,
/// and its counters differ from the serial run's (the contacts do not).
TEST(ParallelRunner, DynamicWithoutDcdCarriesStateSoBlocksWouldChangeItsCounters) {
  const auto l = load(kRope);
  std::vector<FrameReport> out[2];
  for (const int k : {0, 1}) {
    RunOptions options;
    options.method = "dynamic";
    options.frames = parse_frame_range("12:");
    options.query = QuerySet::ccd;
    options.threads = k == 0 ? 1 : 3;
    options.block_samples = 2;
    (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    options.factory_methods_stateless = true;  // the lie under test
    // Slow queries, so that every worker takes blocks (a worker that happened to take all blocks
    // in order would carry the state like a serial run).
    ClipRunner runner(
        *l.motion,
        options,
        [](const skinning::Mesh& mesh,
           const skinning::Topology& topology,
           const culling::MethodOptions& mo) -> std::unique_ptr<culling::CullingMethod> {
          return std::make_unique<SlowMethod>(culling::make_method("dynamic", mesh, topology, mo));
        });
    ASSERT_EQ(runner.plan().threads, k == 0 ? 1 : 3);
    out[k] = collect(runner);
  }
  ASSERT_EQ(out[0].size(), out[1].size());
  bool counters_differ = false;
  for (std::size_t i = 0; i < out[0].size(); ++i) {
    EXPECT_EQ(out[0][i].contacts, out[1][i].contacts) << i;
    counters_differ = counters_differ ||
                      out[0][i].row.counters.bv_tests != out[1][i].row.counters.bv_tests ||
                      out[0][i].row.counters.tt_tests != out[1][i].row.counters.tt_tests;
  }
  EXPECT_TRUE(counters_differ) << "blocks of dynamic --query ccd matched serial: is the carried "
                                  "state gone? then serial_reason can allow it";
}

/// Counts the oneTBB worker threads that join the calling thread's arena while it lives.
class WorkerEntries : public tbb::task_scheduler_observer {
 public:
  WorkerEntries() { observe(true); }
  ~WorkerEntries() override { observe(false); }
  void on_scheduler_entry(bool is_worker) override {
    if (is_worker) ++entries;
  }
  std::atomic<int> entries{0};
};

TEST(ParallelRunner, ASerialRunSegmentsOnItsOwnThread) {
  // CesiumMan-dense has 28,032 triangles: enough for segment_mesh to split its bones and clusters
  // over oneTBB's threads, which `--threads 1` must keep to the calling thread: it hands oneTBB no
  // task, so no worker joins (each test runs in a process of its own). With 2 threads the
  // segmentation is the same.
  const Loaded l = load(test::asset("characters/CesiumMan-dense.glb").string());
  ASSERT_GT(l.motion->mesh().num_triangles(), 20000);
  RunOptions options;
  options.method = "dynamic";
  options.threads = 1;
  std::shared_ptr<const segmentation::Segmentation> serial;
  {
    WorkerEntries workers;
    const RadialViewSetup setup =
        setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
    EXPECT_EQ(workers.entries.load(), 0) << "a worker joined the segmentation of a serial run";
    ASSERT_NE(options.segmentation, nullptr);
    EXPECT_EQ(setup.segmentation_source, "computed (rig weights)");
    EXPECT_GT(setup.atomic_clusters, 0);
    serial = options.segmentation;
  }
  options.threads = 2;
  (void)setup_radial_view(RadialViewArguments{}, l.model, *l.motion, options);
  ASSERT_EQ(options.segmentation->clusters.size(), serial->clusters.size());
  for (std::size_t c = 0; c < serial->clusters.size(); ++c) {
    EXPECT_EQ(options.segmentation->clusters[c].triangles, serial->clusters[c].triangles) << c;
    EXPECT_EQ(options.segmentation->clusters[c].observer.kind, serial->clusters[c].observer.kind);
  }
}

}  // namespace
