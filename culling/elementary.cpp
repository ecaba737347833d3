#include "culling/elementary.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cstdint>
#include <vector>

#include "ccd/after_swept_aabbs.hpp"
#include "ccd/coplanarity_screen.hpp"
#include "ccd/filters.hpp"
#include "culling/pair_sort.hpp"

namespace skelcd::culling {
namespace {

inline Eigen::Vector3d row(const skinning::Positions& x, std::int32_t i) {
  return x.row(static_cast<Eigen::Index>(i)).transpose();
}

}  // namespace

ccd::VertexFaceQuery vertex_face_query(
    const skinning::Positions& xv_t0,
    const skinning::Positions& xv_t1,
    std::int32_t v,
    const skinning::Positions& xf_t0,
    const skinning::Positions& xf_t1,
    const std::array<std::int32_t, 3>& f) {
  return {row(xv_t0, v),
          row(xf_t0, f[0]),
          row(xf_t0, f[1]),
          row(xf_t0, f[2]),
          row(xv_t1, v),
          row(xf_t1, f[0]),
          row(xf_t1, f[1]),
          row(xf_t1, f[2])};
}

ccd::EdgeEdgeQuery edge_edge_query(
    const skinning::Positions& xa_t0,
    const skinning::Positions& xa_t1,
    const std::array<std::int32_t, 2>& ea,
    const skinning::Positions& xb_t0,
    const skinning::Positions& xb_t1,
    const std::array<std::int32_t, 2>& eb) {
  return {row(xa_t0, ea[0]),
          row(xa_t0, ea[1]),
          row(xb_t0, eb[0]),
          row(xb_t0, eb[1]),
          row(xa_t1, ea[0]),
          row(xa_t1, ea[1]),
          row(xb_t1, eb[0]),
          row(xb_t1, eb[1])};
}

namespace {

/// One query's outcome, in its candidate's slot (24 bytes: the doubles first).
struct Outcome {
  double toi_lower = 0;
  double toi_upper = 0;
  bool hit = false;
  bool tested = true;  ///< false: settled without a test (DCD, a certified vertex fan)
  bool kept = true;    ///< false: dropped by the DCD filter (filter_and_run_dcd_tests)
};

/// Per calling thread, reused across calls: room for one window of outcomes
/// (kElementaryOutcomeWindow), never more, whatever the size of the calls. A call over more
/// queries tests them a window at a time; an unbounded buffer grew to the largest block ever seen
/// (about 2 MB after a clip's baseline DCD) and was held for the rest of the run.
/// The parallel loops below run isolated, so a thread waiting for them never picks up another
/// caller's work and re-enters this function with its buffer in use.
thread_local std::vector<Outcome> tl_outcomes;
/// Per calling thread, likewise: which welded vertices have a certified fan at the DCD instant.
thread_local std::vector<std::uint8_t> tl_certified_fans;

/// Calls `test_range(i, count, outcomes)` for consecutive ranges [i, i + count) covering [0, n),
/// the outcome of query i + k into outcomes[k], on this thread or split over oneTBB workers when
/// `threads` > 1 and n is large enough, a window of kElementaryOutcomeWindow queries at a time;
/// then `consume(i, outcome)` for each query of the window, in order. Every outcome goes to its
/// own slot, so the order of `consume` calls is i's whatever the split.
template <typename TestRange, typename Consume>
void evaluate_ranges(
    std::size_t n,
    const ElementaryTests& tests,
    const TestRange& test_range,
    const Consume& consume) {
  if (n == 0) return;
  const std::size_t window = std::min(n, kElementaryOutcomeWindow);
  if (tl_outcomes.size() < window) {
    // Exactly the window: resize alone grows a vector by at least its size, so a thread that had
    // 6,656 outcomes and then a full window kept 13,312 (the scratch bound the tests assert; seen
    // when one process ran a DCD and then these tests).
    tl_outcomes.reserve(window);
    tl_outcomes.resize(window);
  }
  Outcome* const outcomes = tl_outcomes.data();
  const auto report = [&](std::size_t done) {
    if (tests.tests_done != nullptr)
      tests.tests_done->fetch_add(static_cast<std::int64_t>(done), std::memory_order_relaxed);
  };
  const bool parallel = tests.threads > 1 && n >= kParallelElementaryThreshold;
  for (std::size_t first = 0; first < n; first += window) {
    const std::size_t count = std::min(window, n - first);
    if (parallel) {
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_for(
            tbb::blocked_range<std::size_t>(0, count, 64),
            [&](const tbb::blocked_range<std::size_t>& range) {
              test_range(first + range.begin(), range.size(), outcomes + range.begin());
              report(range.size());
            });
      });
    } else {
      constexpr std::size_t kReportEvery = 1024;
      for (std::size_t start = 0; start < count; start += kReportEvery) {
        const std::size_t end = std::min(count, start + kReportEvery);
        test_range(first + start, end - start, outcomes + start);
        report(end - start);
      }
    }
    for (std::size_t i = 0; i < count; ++i) consume(first + i, outcomes[i]);
  }
}

/// Which kernels `tests` hold: the ccd/ kernels, the same without their swept-AABB stage
/// (ccd/after_swept_aabbs.hpp), or others (substituted tests, or one of each).
enum class KernelUse : std::uint8_t { other, product, after_swept_aabbs };

KernelUse kernel_use(const ElementaryTests& tests) {
  using VertexFaceFn = ElementaryTests::VertexFaceFn;
  using EdgeEdgeFn = ElementaryTests::EdgeEdgeFn;
  if (tests.vertex_face == static_cast<VertexFaceFn>(&ccd::vertex_face_ccd) &&
      tests.edge_edge == static_cast<EdgeEdgeFn>(&ccd::edge_edge_ccd)) {
    return KernelUse::product;
  }
  if (tests.vertex_face == static_cast<VertexFaceFn>(&ccd::vertex_face_ccd_after_swept_aabbs) &&
      tests.edge_edge == static_cast<EdgeEdgeFn>(&ccd::edge_edge_ccd_after_swept_aabbs)) {
    return KernelUse::after_swept_aabbs;
  }
  return KernelUse::other;
}

/// evaluate_ranges with `test(i, outcome)` called for each query.
template <typename Test, typename Consume>
void evaluate(
    std::size_t n, const ElementaryTests& tests, const Test& test, const Consume& consume) {
  evaluate_ranges(
      n,
      tests,
      [&](std::size_t first, std::size_t count, Outcome* outcomes) {
        for (std::size_t k = 0; k < count; ++k) test(first + k, outcomes[k]);
      },
      consume);
}

/// Tests queries [first, first + count) into outcomes, four at a time: the coplanarity screens of
/// the four (ccd/coplanarity_screen.hpp; `screen(quads)`) settle those they certify apart, and
/// `test(i, outcome, screens, lane)` tests the others. `quad(i)` gives query i's four point
/// indices; a short last group repeats its last query.
template <typename Quad, typename Screen, typename Test>
void screened_range(
    std::size_t first,
    std::size_t count,
    Outcome* outcomes,
    const Quad& quad,
    const Screen& screen,
    const Test& test) {
  std::array<std::array<std::int32_t, 4>, 4> quads;
  for (std::size_t g = 0; g < count; g += 4) {
    const std::size_t m = std::min<std::size_t>(4, count - g);
    for (std::size_t k = 0; k < 4; ++k) quads[k] = quad(first + g + std::min(k, m - 1));
    const ccd::CoplanarityScreens screens = screen(quads);
    for (std::size_t k = 0; k < m; ++k) {
      if ((screens.apart >> k & 1u) != 0) {
        outcomes[g + k] = Outcome{.hit = false};
      } else {
        test(first + g + k, outcomes[g + k], screens, static_cast<int>(k));
      }
    }
  }
}

}  // namespace

void run_ccd_tests(
    const FeatureTopology& topology,
    const FeatureCandidates& candidates,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1,
    const ElementaryTests& tests,
    ccd::Accuracy accuracy,
    const ccd::CcdOptions& options,
    FrameResult& out,
    ContactOrder order) {
  assert(tests.vertex_face != nullptr && tests.edge_edge != nullptr);
  const std::size_t first = out.contacts.size();
  Counters& c = out.counters;
  // The product's kernels asked for contact itself: each group of four queries is screened at
  // once first (ccd/coplanarity_screen.hpp), and the kernel goes on from the stage after its
  // screen for those the screen leaves — after its swept-AABB stage, which the plain kernels run
  // first and the *_after_swept_aabbs ones skip (after_swept_aabbs.hpp): the same decisions,
  // without assembling and calling for the queries the screen settles.
  const KernelUse use = kernel_use(tests);
  const bool screened = use != KernelUse::other && accuracy == ccd::Accuracy::conservative &&
                        options.min_separation == 0.0;
  const bool swept_first = use == KernelUse::product;
  const double* const xd_t0 = x_t0.data();  // row-major: vertex v at 3 v
  const double* const xd_t1 = x_t1.data();
  // Vertex-face queries: outcomes in candidate order, the hits appended in that order.
  const auto vf_query = [&](std::size_t i) {
    const VertexFacePair& p = candidates.vf[i];
    return vertex_face_query(x_t0, x_t1, p.vertex, x_t0, x_t1, topology.triangle(p.face));
  };
  const auto vf_test = [&](std::size_t i, Outcome& o) {
    const ccd::CcdResult r = tests.vertex_face(vf_query(i), accuracy, options);
    o = {.toi_lower = r.toi_lower, .toi_upper = r.toi_upper, .hit = r.hit};
  };
  const auto vf_quad = [&](std::size_t i) {
    const VertexFacePair& p = candidates.vf[i];
    const auto& f = topology.triangle(p.face);
    return std::array<std::int32_t, 4>{p.vertex, f[0], f[1], f[2]};
  };
  const auto vf_screen = [&](const std::array<std::array<std::int32_t, 4>, 4>& quads) {
    return ccd::vertex_face_screen_x4(xd_t0, xd_t1, quads);
  };
  const auto vf_rest = [&](std::size_t i, Outcome& o, const ccd::CoplanarityScreens& s, int k) {
    const ccd::VertexFaceQuery q = vf_query(i);
    const ccd::CcdResult r = swept_first && ccd::swept_aabbs_disjoint(q)
                                 ? ccd::CcdResult{}
                                 : ccd::vertex_face_ccd_after_screen(q, options, s, k);
    o = {.toi_lower = r.toi_lower, .toi_upper = r.toi_upper, .hit = r.hit};
  };
  evaluate_ranges(
      candidates.vf.size(),
      tests,
      [&](std::size_t from, std::size_t count, Outcome* outcomes) {
        if (screened) {
          screened_range(from, count, outcomes, vf_quad, vf_screen, vf_rest);
        } else {
          for (std::size_t k = 0; k < count; ++k) vf_test(from + k, outcomes[k]);
        }
      },
      [&](std::size_t i, const Outcome& o) {
        ++c.vf_tests;
        if (!o.hit) return;
        ++c.vf_contacts;
        const VertexFacePair& p = candidates.vf[i];
        room_for_one_more(out.contacts);
        out.contacts.push_back({CcdContact::Kind::vf, p.vertex, p.face, o.toi_lower, o.toi_upper});
      });
  // Edge-edge queries, likewise.
  const auto ee_query = [&](std::size_t i) {
    const EdgeEdgePair& p = candidates.ee[i];
    return edge_edge_query(x_t0, x_t1, topology.edge(p.a), x_t0, x_t1, topology.edge(p.b));
  };
  const auto ee_test = [&](std::size_t i, Outcome& o) {
    const ccd::CcdResult r = tests.edge_edge(ee_query(i), accuracy, options);
    o = {.toi_lower = r.toi_lower, .toi_upper = r.toi_upper, .hit = r.hit};
  };
  const auto ee_quad = [&](std::size_t i) {
    const EdgeEdgePair& p = candidates.ee[i];
    const auto& a = topology.edge(p.a);
    const auto& b = topology.edge(p.b);
    return std::array<std::int32_t, 4>{a[0], a[1], b[0], b[1]};
  };
  const auto ee_screen = [&](const std::array<std::array<std::int32_t, 4>, 4>& quads) {
    return ccd::edge_edge_screen_x4(xd_t0, xd_t1, quads);
  };
  const auto ee_rest = [&](std::size_t i, Outcome& o, const ccd::CoplanarityScreens& s, int k) {
    const ccd::EdgeEdgeQuery q = ee_query(i);
    const ccd::CcdResult r = swept_first && ccd::swept_aabbs_disjoint(q)
                                 ? ccd::CcdResult{}
                                 : ccd::edge_edge_ccd_after_screen(q, options, s, k);
    o = {.toi_lower = r.toi_lower, .toi_upper = r.toi_upper, .hit = r.hit};
  };
  evaluate_ranges(
      candidates.ee.size(),
      tests,
      [&](std::size_t from, std::size_t count, Outcome* outcomes) {
        if (screened) {
          screened_range(from, count, outcomes, ee_quad, ee_screen, ee_rest);
        } else {
          for (std::size_t k = 0; k < count; ++k) ee_test(from + k, outcomes[k]);
        }
      },
      [&](std::size_t i, const Outcome& o) {
        ++c.ee_tests;
        if (!o.hit) return;
        ++c.ee_contacts;
        const EdgeEdgePair& p = candidates.ee[i];
        room_for_one_more(out.contacts);
        out.contacts.push_back({CcdContact::Kind::ee, p.a, p.b, o.toi_lower, o.toi_upper});
      });
  if (order == ContactOrder::sorted) sort_contacts(std::span(out.contacts).subspan(first));
}

void run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    FrameResult& out) {
  run_dcd_tests(
      topology,
      pairs,
      x,
      tests,
      pairs.empty() ? std::span<const std::uint8_t>{} : certify_dcd_fans(topology, x, tests),
      out);
}

bool ccd_uses_fans(
    const FeatureTopology& topology, const ElementaryTests& tests, const ccd::CcdOptions& options) {
  return options.min_separation == 0.0 && topology.fans().num_fans() > 0 &&
         tests.vertex_face == static_cast<ElementaryTests::VertexFaceFn>(&ccd::vertex_face_ccd) &&
         tests.edge_edge == static_cast<ElementaryTests::EdgeEdgeFn>(&ccd::edge_edge_ccd);
}

std::span<const std::uint8_t> certify_dcd_fans(
    const FeatureTopology& topology, const skinning::Positions& x, const ElementaryTests& tests) {
  // Certified vertex fans settle pairs that share a corner without a test — only for the exact
  // test they stand for (a test of another definition sees every pair).
  if (tests.triangles != &ccd::triangles_intersect || topology.fans().num_fans() == 0) return {};
  topology.fans().certify(x, tl_certified_fans);
  return tl_certified_fans;
}

namespace {

/// Prefetch distances of dcd_tests, in pairs.
constexpr std::size_t kFar = 16;
constexpr std::size_t kNear = 8;
/// dcd_tests prefetches from this many triangles on. Below it, the planes, corner ids and
/// positions a test reads (about 72 bytes per triangle) stay in the caches and the prefetches are
/// only instructions: without them the DCD is 2-4 % faster on the bundled characters and the
/// 18k-triangle cloth-funnel step, with them 5 % faster on the 92k-triangle cloth-ball step
/// (bench/real/ab_dcd.py, 2026-11-28).
constexpr std::int32_t kPrefetchFrom = 32768;

void dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::span<const std::uint8_t> certified,
    std::span<const ccd::TrianglePlane> planes,
    bool filter,
    bool sorted,
    FrameResult& out) {
  assert(tests.triangles != nullptr);
  assert(
      planes.empty() || (tests.triangles == &ccd::triangles_intersect &&
                         planes.size() == static_cast<std::size_t>(topology.num_triangles())));
  const std::size_t first = out.dcd_pairs.size();
  // The flags are read by the workers too: a span of the caller's, not their own thread_local.
  const bool use_fans = !certified.empty();
  assert(!use_fans || certified.size() == static_cast<std::size_t>(topology.num_vertices()));
  const bool prefetch = topology.num_triangles() >= kPrefetchFrom;
  // Outcomes in pair order, the intersecting pairs appended in that order.
  evaluate(
      pairs.size(),
      tests,
      [&](std::size_t i, Outcome& o) {
        // The pairs' triangles are scattered over the mesh: ask for a later pair's data ahead, its
        // corner ids and planes kFar pairs on, its corners' positions kNear pairs on.
        if (prefetch && i + kFar < pairs.size()) {
          const TrianglePair& f = pairs[i + kFar];
          __builtin_prefetch(&topology.triangle(f.a));
          __builtin_prefetch(&topology.triangle(f.b));
          if (!planes.empty()) {
            __builtin_prefetch(&planes[static_cast<std::size_t>(f.a)]);
            __builtin_prefetch(&planes[static_cast<std::size_t>(f.a)].m[2]);
            __builtin_prefetch(&planes[static_cast<std::size_t>(f.b)]);
            __builtin_prefetch(&planes[static_cast<std::size_t>(f.b)].m[2]);
          }
        }
        if (prefetch && i + kNear < pairs.size()) {
          const TrianglePair& f = pairs[i + kNear];
          for (const std::int32_t t : {f.a, f.b}) {
            for (const std::int32_t v : topology.triangle(t)) __builtin_prefetch(x.data() + 3 * v);
          }
        }
        const TrianglePair& p = pairs[i];
        assert(p.a < p.b);
        o.kept = true;
        if (filter && topology.triangles_excluded(p.a, p.b)) {
          o = Outcome{.hit = false, .tested = false, .kept = false};
          return;
        }
        int count = 0;
        const ccd::SharedCorners shared = topology.shared_corners(p.a, p.b, count);
        if (filter && count >= 3) {  // a duplicate face on the same three vertices
          o = Outcome{.hit = false, .tested = false, .kept = false};
          return;
        }
        const auto& ta = topology.triangle(p.a);
        if (use_fans && count > 0) {
          for (std::size_t k = 0; k < 3; ++k) {
            if (shared[k] >= 0 && certified[static_cast<std::size_t>(ta[k])] != 0) {
              o.hit = false;
              o.tested = false;
              return;
            }
          }
        }
        o.tested = true;
        const auto& tb = topology.triangle(p.b);
        // A pair without shared corners: a's corners against b's plane by the filter first, from
        // the positions in place; about half stop here (docs/culling.md "What the blocks do").
        ccd::FirstSides first_sides;
        const bool split = count == 0 && !planes.empty();
        if (split) {
          const double* const xd = x.data();  // row-major: vertex v at xd + 3 v
          if (ccd::first_sides_separate(
                  xd + 3 * static_cast<std::size_t>(ta[0]),
                  xd + 3 * static_cast<std::size_t>(ta[1]),
                  xd + 3 * static_cast<std::size_t>(ta[2]),
                  xd + 3 * static_cast<std::size_t>(tb[0]),
                  planes[static_cast<std::size_t>(p.b)],
                  first_sides)) {
            o.hit = false;
            return;
          }
        }
        const ccd::TriangleTriangleQuery q{
            row(x, ta[0]),
            row(x, ta[1]),
            row(x, ta[2]),
            row(x, tb[0]),
            row(x, tb[1]),
            row(x, tb[2])};
        if (planes.empty()) {
          o.hit = tests.triangles(q, shared);
        } else if (split) {
          o.hit = ccd::triangles_intersect_after_first_sides(
              q,
              planes[static_cast<std::size_t>(p.a)],
              planes[static_cast<std::size_t>(p.b)],
              first_sides);
        } else {
          o.hit = ccd::triangles_intersect_with_planes(
              q,
              shared,
              planes[static_cast<std::size_t>(p.a)],
              planes[static_cast<std::size_t>(p.b)]);
        }
      },
      [&](std::size_t i, const Outcome& o) {
        // Pairs settled by a fan are candidates (candidate_pairs) but not tests.
        if (filter && o.kept) ++out.counters.candidate_pairs;
        if (o.tested) ++out.counters.tt_tests;
        if (!o.hit) return;
        ++out.counters.dcd_pairs;
        room_for_one_more(out.dcd_pairs);
        out.dcd_pairs.push_back(pairs[i]);
      });
  if (sorted) {
    sort_pairs(std::span(out.dcd_pairs).subspan(first));
  }
}

}  // namespace

void run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::span<const std::uint8_t> certified,
    FrameResult& out) {
  dcd_tests(topology, pairs, x, tests, certified, {}, /*filter=*/false, /*sorted=*/true, out);
}

std::size_t elementary_outcome_capacity() { return tl_outcomes.capacity(); }

void filter_and_run_dcd_tests(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::span<const std::uint8_t> certified,
    std::span<const ccd::TrianglePlane> planes,
    FrameResult& out) {
  dcd_tests(topology, pairs, x, tests, certified, planes, /*filter=*/true, /*sorted=*/false, out);
}

void dcd_planes(
    const FeatureTopology& topology,
    const skinning::Positions& x,
    const ElementaryTests& tests,
    std::vector<ccd::TrianglePlane>& planes) {
  if (tests.triangles != &ccd::triangles_intersect) {
    planes.clear();
    return;
  }
  planes.resize(static_cast<std::size_t>(topology.num_triangles()));
  for (std::int32_t t = 0; t < topology.num_triangles(); ++t) {
    const auto& c = topology.triangle(t);
    planes[static_cast<std::size_t>(t)] =
        ccd::triangle_plane(row(x, c[0]), row(x, c[1]), row(x, c[2]));
  }
}

}  // namespace skelcd::culling
