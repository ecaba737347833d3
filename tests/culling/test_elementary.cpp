// The elementary stage (culling/elementary.hpp) on calls larger than its outcome window: every
// query is tested once, the hits come out in candidate order with their own times, and the
// scratch each thread keeps between calls stays one window whatever the size of the calls.

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <thread>
#include <vector>

#include "ccd/after_swept_aabbs.hpp"
#include "culling/candidates.hpp"
#include "culling/elementary.hpp"
#include "culling/feature_topology.hpp"
#include "tests/culling/procedural_meshes.hpp"
#include "tests/culling/renamed_kernels.hpp"
#include "tests/culling/test_dual_cone_scenes.hpp"
#include "tests/support/test_support.hpp"

namespace skelcd::culling {
namespace {

/// `n` disjoint triangles, triangle i's corners at x = i: (i,0,0), (i,1,0), (i,0,1). A test
/// function can tell from a query's coordinates which triangles or vertex it was given.
skinning::Mesh strip(int n) {
  skinning::Mesh mesh;
  mesh.rest_positions.resize(3 * n, 3);
  mesh.triangles.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    const double x = i;
    mesh.rest_positions.row(3 * i) << x, 0, 0;
    mesh.rest_positions.row(3 * i + 1) << x, 1, 0;
    mesh.rest_positions.row(3 * i + 2) << x, 0, 1;
    mesh.triangles.row(i) << 3 * i, 3 * i + 1, 3 * i + 2;
  }
  mesh.face_part.assign(static_cast<std::size_t>(n), 0);
  mesh.part_names = {"strip"};
  return mesh;
}

std::int32_t triangle_at(const Eigen::Vector3d& corner0) {
  return static_cast<std::int32_t>(std::lround(corner0.x()));
}

std::int32_t vertex_at(const Eigen::Vector3d& p) {
  return 3 * triangle_at(p) + (p.y() > 0.5 ? 1 : (p.z() > 0.5 ? 2 : 0));
}

bool pair_hits(std::int32_t a, std::int32_t b) { return (31 * a + b) % 5 == 0; }

bool triangles_by_index(const ccd::TriangleTriangleQuery& q, const ccd::SharedCorners&) {
  return pair_hits(triangle_at(q.a0), triangle_at(q.b0));
}

bool vertex_face_hits(std::int32_t v, std::int32_t f) { return (v + 3 * f) % 7 == 0; }
double vertex_face_toi(std::int32_t v, std::int32_t f) { return (v * 1000 + f) * 1e-8; }

ccd::CcdResult vertex_face_by_index(
    const ccd::VertexFaceQuery& q, ccd::Accuracy, const ccd::CcdOptions&) {
  const std::int32_t v = vertex_at(q.v_t0);
  const std::int32_t f = triangle_at(q.f0_t0);
  if (!vertex_face_hits(v, f)) return {};
  const double toi = vertex_face_toi(v, f);
  return {.hit = true, .toi_lower = toi, .toi_upper = toi + 1e-9};
}

ccd::CcdResult edge_edge_never(const ccd::EdgeEdgeQuery&, ccd::Accuracy, const ccd::CcdOptions&) {
  return {};
}

struct Strip {
  skinning::Mesh mesh;
  skinning::Topology topology;
  skinning::Positions x;
  FeatureTopology features;
  explicit Strip(int n)
      : mesh(strip(n)),
        topology(test::simple_topology(mesh)),
        x(test::welded(topology, mesh.rest_positions)),
        features(mesh, topology) {}
};

TEST(Elementary, DcdCallsLargerThanTheWindowKeepEveryOutcomeAndAWindowOfScratch) {
  const Strip s(200);
  std::vector<TrianglePair> pairs;
  std::vector<TrianglePair> expected;
  for (std::int32_t a = 0; a < 200; ++a) {
    for (std::int32_t b = a + 1; b < 200; ++b) {
      pairs.push_back({a, b});
      if (pair_hits(a, b)) expected.push_back({a, b});
    }
  }
  // 19,900 pairs: two full windows and a part of one.
  ASSERT_GT(pairs.size(), 2 * kElementaryOutcomeWindow);
  ASSERT_NE(pairs.size() % kElementaryOutcomeWindow, 0u);
  for (const std::int32_t threads : {1, 2}) {
    std::atomic<std::int64_t> done{0};
    const ElementaryTests tests = with_ccd_defaults(
        {.triangles = &triangles_by_index, .threads = threads, .tests_done = &done});
    FrameResult sorted;
    run_dcd_tests(s.features, pairs, s.x, tests, sorted);
    EXPECT_EQ(sorted.dcd_pairs, expected) << threads << " threads";
    EXPECT_EQ(sorted.counters.tt_tests, static_cast<std::int64_t>(pairs.size()));
    EXPECT_EQ(sorted.counters.dcd_pairs, static_cast<std::int64_t>(expected.size()));
    EXPECT_EQ(done.load(), static_cast<std::int64_t>(pairs.size()));
    // The filtering pass appends in the order of `pairs`, which is sorted here.
    FrameResult filtered;
    filter_and_run_dcd_tests(s.features, pairs, s.x, tests, {}, {}, filtered);
    EXPECT_EQ(filtered.dcd_pairs, expected) << threads << " threads";
    EXPECT_EQ(filtered.counters.candidate_pairs, static_cast<std::int64_t>(pairs.size()));
    EXPECT_LE(elementary_outcome_capacity(), kElementaryOutcomeWindow) << threads << " threads";
    // Then a small call: the same bound, and nothing of the big call's outcomes.
    FrameResult small;
    run_dcd_tests(s.features, std::span(pairs).first(10), s.x, tests, small);
    EXPECT_EQ(small.counters.tt_tests, 10);
    EXPECT_EQ(small.dcd_pairs, std::vector<TrianglePair>(expected.begin(), expected.begin() + 2));
    EXPECT_LE(elementary_outcome_capacity(), kElementaryOutcomeWindow);
  }
}

// The thread's outcome buffer grown in two steps — a call of 13/16 of a window, then one larger
// than a window — is still one window: a vector's own growth would have doubled 6,656 to 13,312
// (what a test process running a DCD before these tests showed).
// Findings double up to 256 KiB and then grow by whole 2 MiB blocks (frame_result.hpp), which
// the executable places on huge pages whole; what was pushed stays as pushed.
template <class T, class Make>
void expect_grown_in_whole_huge_pages(std::size_t n, const Make& make) {
  constexpr std::size_t kQuarterMiB = std::size_t{256} << 10;
  constexpr std::size_t kTwoMiB = std::size_t{2} << 20;
  std::vector<T> v;
  std::vector<std::size_t> capacities;
  for (std::size_t i = 0; i < n; ++i) {
    room_for_one_more(v);
    v.push_back(make(i));
    if (capacities.empty() || capacities.back() != v.capacity()) capacities.push_back(v.capacity());
  }
  ASSERT_EQ(v.size(), n);
  for (std::size_t i = 0; i < n; ++i) ASSERT_TRUE(v[i] == make(i)) << i;
  std::size_t past = 0;
  for (std::size_t k = 0; k < capacities.size(); ++k) {
    const std::size_t bytes = capacities[k] * sizeof(T);
    if (k > 0 && capacities[k - 1] * sizeof(T) >= kQuarterMiB) {
      EXPECT_EQ(bytes % kTwoMiB, 0U) << capacities[k];
      EXPECT_GE(capacities[k], 2 * capacities[k - 1]);  // still geometric: few moves
      ++past;
    } else if (k > 0) {
      EXPECT_LE(bytes, 2 * kQuarterMiB) << capacities[k];  // push_back's own growth
    }
  }
  EXPECT_GE(past, 2U);
}

TEST(Elementary, FindingsGrowByWholeHugePagesPastAQuarterMebibyte) {
  expect_grown_in_whole_huge_pages<CcdContact>(300'000, [](std::size_t i) {
    const auto id = static_cast<std::int32_t>(i);
    return CcdContact{CcdContact::Kind::ee, id, id + 1, 0.25, 0.5};
  });
  expect_grown_in_whole_huge_pages<TrianglePair>(1'200'000, [](std::size_t i) {
    const auto id = static_cast<std::int32_t>(i);
    return TrianglePair{id, id + 7};
  });
}

TEST(Elementary, ScratchGrownInTwoStepsStaysOneWindow) {
  const Strip s(200);
  std::vector<TrianglePair> pairs;
  for (std::int32_t a = 0; a < 200; ++a) {
    for (std::int32_t b = a + 1; b < 200; ++b) pairs.push_back({a, b});
  }
  ASSERT_GT(pairs.size(), kElementaryOutcomeWindow);
  const ElementaryTests tests = with_ccd_defaults({.triangles = &triangles_by_index, .threads = 1});
  // A fresh thread: this one's buffer may have grown in an earlier test of the same process.
  std::thread([&] {
    FrameResult first;
    run_dcd_tests(
        s.features, std::span(pairs).first(kElementaryOutcomeWindow / 16 * 13), s.x, tests, first);
    FrameResult second;
    run_dcd_tests(s.features, pairs, s.x, tests, second);
    EXPECT_EQ(second.counters.tt_tests, static_cast<std::int64_t>(pairs.size()));
    EXPECT_LE(elementary_outcome_capacity(), kElementaryOutcomeWindow);
  }).join();
}

TEST(Elementary, CcdCallsLargerThanTheWindowKeepEachHitsOwnTimes) {
  const Strip s(100);
  FeatureCandidates candidates;
  std::vector<CcdContact> expected;
  for (std::int32_t v = 0; v < 300; ++v) {
    for (std::int32_t f = 0; f < 100; ++f) {
      if (f == v / 3) continue;
      candidates.vf.push_back({v, f});
      if (vertex_face_hits(v, f)) {
        const double toi = vertex_face_toi(v, f);
        expected.push_back({CcdContact::Kind::vf, v, f, toi, toi + 1e-9});
      }
    }
  }
  ASSERT_GT(candidates.vf.size(), kElementaryOutcomeWindow);
  ASSERT_NE(candidates.vf.size() % kElementaryOutcomeWindow, 0u);
  for (const std::int32_t threads : {1, 2}) {
    const ElementaryTests tests = with_ccd_defaults(
        {.vertex_face = &vertex_face_by_index, .edge_edge = &edge_edge_never, .threads = threads});
    FrameResult out;
    run_ccd_tests(s.features, candidates, s.x, s.x, tests, ccd::Accuracy::conservative, {}, out);
    EXPECT_EQ(out.contacts, expected) << threads << " threads";
    EXPECT_EQ(out.counters.vf_tests, static_cast<std::int64_t>(candidates.vf.size()));
    EXPECT_EQ(out.counters.vf_contacts, static_cast<std::int64_t>(expected.size()));
    EXPECT_LE(elementary_outcome_capacity(), kElementaryOutcomeWindow);
  }
}

/// Every pair of triangles a < b whose swept boxes over x_t0 → x_t1 overlap (sweep and prune on
/// x): the candidates of a whole-mesh CCD without a hierarchy.
std::vector<TrianglePair> swept_box_pairs(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  const std::int32_t n = topology.num_triangles();
  std::vector<std::array<double, 6>> box(static_cast<std::size_t>(n));
  for (std::int32_t t = 0; t < n; ++t) {
    auto& b = box[static_cast<std::size_t>(t)];
    b = {1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    for (const std::int32_t v : topology.triangle(t)) {
      for (const skinning::Positions* x : {&x_t0, &x_t1}) {
        for (int k = 0; k < 3; ++k) {
          const auto i = static_cast<std::size_t>(k);
          b[i] = std::min(b[i], (*x)(v, k));
          b[i + 3] = std::max(b[i + 3], (*x)(v, k));
        }
      }
    }
  }
  std::vector<std::int32_t> order(static_cast<std::size_t>(n));
  for (std::int32_t t = 0; t < n; ++t) order[static_cast<std::size_t>(t)] = t;
  std::sort(order.begin(), order.end(), [&](std::int32_t a, std::int32_t b) {
    return box[static_cast<std::size_t>(a)][0] < box[static_cast<std::size_t>(b)][0];
  });
  std::vector<TrianglePair> pairs;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto& a = box[static_cast<std::size_t>(order[i])];
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const auto& b = box[static_cast<std::size_t>(order[j])];
      if (b[0] > a[3]) break;
      if (b[1] <= a[4] && a[1] <= b[4] && b[2] <= a[5] && a[2] <= b[5]) {
        pairs.push_back({std::min(order[i], order[j]), std::max(order[i], order[j])});
      }
    }
  }
  return pairs;
}

TEST(FeatureStage, EveryBuildGivesTheSamePairsInTheSameOrderOnTheClothFunnelStep) {
  // ccd_candidates_from_triangle_pairs runs an AVX-512 VL build of its feature stage where the CPU
  // has it, else an AVX2 build (both on EndPositionsWide), else its SSE2 build: the same pairs in
  // the same order and the same counters, with and without the interval's vertex fans, on a real
  // step whose triangle pairs the face diagonals drop in numbers; the wide builds also from the
  // positions packed a line per vertex (PackedEnds, as the methods hand them over). A build the
  // CPU lacks runs the widest below it (the runs then compare a build with itself).
  const test::OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  const FeatureTopology features(s.mesh, s.topo);
  const skinning::Positions& x_t0 = s.frames[0];
  const skinning::Positions& x_t1 = s.frames[1];
  const std::vector<TrianglePair> pairs = swept_box_pairs(features, x_t0, x_t1);
  ASSERT_GT(pairs.size(), 50000u);
  PackedEnds packed;
  packed.pack(x_t0, x_t1);
  using Build = detail::FeatureStageBuild;
  for (const bool with_fans : {false, true}) {
    SCOPED_TRACE(with_fans ? "with fans" : "without fans");
    const auto run = [&](Build build, const double* packed_ends = nullptr) {
      detail::force_feature_stage_build(build);
      IntervalFans fans;
      fans.start(features.fans(), x_t0, x_t1, features.num_vertices());
      FeatureCandidates out;
      Counters counters;
      ccd_candidates_from_triangle_pairs<3>(
          features,
          pairs,
          FeatureBounds<3>{},
          out,
          counters,
          with_fans ? &fans : nullptr,
          {&x_t0, &x_t1, packed_ends});
      detail::force_feature_stage_build(Build::best);
      return std::make_pair(std::move(out), counters);
    };
    const auto [baseline, baseline_counters] = run(Build::baseline);
    EXPECT_GT(baseline.ee.size(), 2000u);
    for (const Build build : {Build::avx2, Build::avx512}) {
      SCOPED_TRACE(build == Build::avx2 ? "AVX2" : "AVX-512 VL");
      for (const double* packed_ends : {static_cast<const double*>(nullptr), packed.data()}) {
        SCOPED_TRACE(packed_ends != nullptr ? "packed ends" : "positions");
        const auto [wide, wide_counters] = run(build, packed_ends);
        EXPECT_TRUE(wide.vf == baseline.vf);
        EXPECT_TRUE(wide.ee == baseline.ee);
        EXPECT_EQ(wide_counters.candidate_pairs, baseline_counters.candidate_pairs);
        EXPECT_EQ(wide_counters.feature_bv_tests, baseline_counters.feature_bv_tests);
      }
    }
  }
}

TEST(FeatureStage, PackedEndsHoldEachVertexAtBothEndsInOneAlignedLine) {
  // The layout the AVX2 feature stage loads: (x, y, z, z) at t0, then at t1, 64-byte aligned.
  const test::OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  PackedEnds packed;
  EXPECT_EQ(packed.data(), nullptr);
  packed.pack(s.frames[0], s.frames[1]);
  const double* d = packed.data();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(reinterpret_cast<std::uintptr_t>(d) % 64, 0u);
  for (Eigen::Index v = 0; v < s.frames[0].rows(); ++v) {
    const double* line = d + 8 * v;
    for (Eigen::Index k = 0; k < 3; ++k) {
      ASSERT_EQ(line[k], s.frames[0](v, k)) << v;
      ASSERT_EQ(line[4 + k], s.frames[1](v, k)) << v;
    }
    ASSERT_EQ(line[3], s.frames[0](v, 2)) << v;
    ASSERT_EQ(line[7], s.frames[1](v, 2)) << v;
  }
}

TEST(Elementary, ScreenedQueriesFindExactlyWhatTheKernelFindsForEachQuery) {
  // run_ccd_tests screens the product's kernels' queries four at a time and goes on from the
  // screen for the queries it leaves (ccd/coplanarity_screen.hpp). On a real step — the
  // cloth-funnel's pinch, every feature pair of its overlapping swept boxes — that finds the
  // contacts, times and counters that calling the kernel for every query finds: with the full
  // kernels, with the kernels after the swept boxes (as the traversing methods call them), on one
  // thread and on two.
  const test::OpenScene s = test::cloth_funnel_scene(test::asset("cloth-funnel/frames"));
  const FeatureTopology features(s.mesh, s.topo);
  const skinning::Positions& x_t0 = s.frames[0];
  const skinning::Positions& x_t1 = s.frames[1];
  const std::vector<TrianglePair> pairs = swept_box_pairs(features, x_t0, x_t1);
  FeatureCandidates candidates;
  Counters ignored;
  ccd_candidates_from_triangle_pairs<3>(
      features, pairs, FeatureBounds<3>{}, candidates, ignored, nullptr, {&x_t0, &x_t1});
  ASSERT_GT(candidates.vf.size(), 1000u);
  ASSERT_GT(candidates.ee.size(), 2000u);
  const auto run = [&](ElementaryTests tests, std::int32_t threads) {
    tests.threads = threads;
    FrameResult out;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      run_ccd_tests(
          features,
          candidates,
          x_t0,
          x_t1,
          with_ccd_defaults(tests),
          ccd::Accuracy::conservative,
          {},
          out);
    });
    return out;
  };
  // The kernels under other names (renamed_kernels.hpp): called for every query, unscreened.
  const FrameResult want = run(
      {.vertex_face = &test::renamed_vertex_face_ccd, .edge_edge = &test::renamed_edge_edge_ccd},
      1);
  // The step's contacts (107 EE and 27 VF in the whole check) are among these candidates.
  EXPECT_GT(want.counters.ee_contacts, 50);
  EXPECT_GT(want.counters.vf_contacts, 10);
  const ElementaryTests after_boxes{
      .vertex_face = &ccd::vertex_face_ccd_after_swept_aabbs,
      .edge_edge = &ccd::edge_edge_ccd_after_swept_aabbs};
  for (const std::int32_t threads : {1, 2}) {
    for (const ElementaryTests& tests : {ElementaryTests{}, after_boxes}) {
      const FrameResult got = run(tests, threads);
      EXPECT_EQ(got.contacts, want.contacts) << threads << " threads";  // ids and times
      EXPECT_EQ(got.counters.vf_tests, want.counters.vf_tests);
      EXPECT_EQ(got.counters.ee_tests, want.counters.ee_tests);
    }
  }
}

}  // namespace
}  // namespace skelcd::culling
