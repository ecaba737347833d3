#include "culling/candidates.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <initializer_list>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace skelcd::culling {
namespace {

inline std::size_t at(std::int32_t i) { return static_cast<std::size_t>(i); }

inline bool is_corner(std::int32_t v, const std::array<std::int32_t, 3>& t) {
  return v == t[0] || v == t[1] || v == t[2];
}

/// Triangles with corners a and b share a corner whose fan is certified over the interval.
inline bool share_certified_corner(
    const std::array<std::int32_t, 3>& a,
    const std::array<std::int32_t, 3>& b,
    IntervalFans& fans) {
  for (const std::int32_t v : a) {
    if (is_corner(v, b) && fans.certified(v)) return true;
  }
  return false;
}

inline bool share_endpoint(
    const std::array<std::int32_t, 2>& a, const std::array<std::int32_t, 2>& b) {
  return a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1];
}

}  // namespace

template <int N>
void FeatureBounds<N>::derive(const FeatureTopology& topology, bool with_edges) {
  const auto num_edges = with_edges ? static_cast<std::size_t>(topology.num_edges()) : 0;
  const auto num_faces = static_cast<std::size_t>(topology.num_triangles());
  if (with_edges) edges.resize(num_edges);
  triangles.resize(num_faces);
  for (std::size_t e = 0; e < num_edges; ++e) {
    const auto& ed = topology.edge(static_cast<std::int32_t>(e));
    Dop<N> d = vertices[at(ed[0])];
    d.merge(vertices[at(ed[1])]);
    edges[e] = d;
  }
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto& t = topology.triangle(static_cast<std::int32_t>(f));
    Dop<N> d = vertices[at(t[0])];
    d.merge(vertices[at(t[1])]);
    d.merge(vertices[at(t[2])]);
    triangles[f] = d;
  }
}

template <int N>
void FeatureBounds<N>::static_triangles(
    const FeatureTopology& topology, const skinning::Positions& x) {
  vertices.clear();
  const auto num_faces = static_cast<std::size_t>(topology.num_triangles());
  triangles.resize(num_faces);
  const double* const p = x.data();  // row-major: vertex v at p + 3 v
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto& t = topology.triangle(static_cast<std::int32_t>(f));
    const double* c = p + 3 * at(t[0]);
    Dop<N> d = Dop<N>::of_point(c[0], c[1], c[2]);
    for (std::size_t k = 1; k < 3; ++k) {
      c = p + 3 * at(t[k]);
      d.merge(Dop<N>::of_point(c[0], c[1], c[2]));
    }
    triangles[f] = d;
  }
}

namespace {

/// What the feature stage tests a feature pair on: the swept volumes of the interval
/// (FeatureBounds). A face's is its triangle's; an edge's the union of its endpoints' (bit for bit
/// what FeatureBounds::derive stores), formed from corner volumes the VF pairs have just read, so
/// that no per-edge volumes need be held (bounded memory).
template <int N>
struct SweptVolumes {
  /// The triangles' volumes overlap: the traversal tested them.
  static constexpr bool kTrianglesFirst = false;
  const FeatureBounds<N>& bounds;

  [[nodiscard]] const Dop<N>& vertex(std::int32_t v) const { return bounds.vertices[at(v)]; }
  [[nodiscard]] const Dop<N>& face(std::int32_t f, const std::array<std::int32_t, 3>&) const {
    return bounds.triangles[at(f)];
  }
  [[nodiscard]] Dop<N> edge(const std::array<std::int32_t, 2>& ends) const {
    Dop<N> d = bounds.vertices[at(ends[0])];
    d.merge(bounds.vertices[at(ends[1])]);
    return d;
  }
  /// Overlap of two closed volumes as one bit, without branches: about half the feature pairs of
  /// a candidate triangle pair overlap, so a branch on each comparison is mispredicted often.
  [[nodiscard]] static bool meet(const Dop<N>& a, const Dop<N>& b) {
    bool ok = true;
    for (std::size_t k = 0; k < static_cast<std::size_t>(N); ++k) {
      ok = ok & (a.lo[k] <= b.hi[k]) & (b.lo[k] <= a.hi[k]);
    }
    return ok;
  }
  /// Asks for a face's volume and its corners' (8-byte aligned: a volume's last byte may start
  /// one more cache line).
  void prefetch(std::int32_t f, const std::array<std::int32_t, 3>& corners) const {
    prefetch_volume(bounds.triangles[at(f)]);
    for (const std::int32_t v : corners) prefetch_volume(bounds.vertices[at(v)]);
  }
  static void prefetch_volume(const Dop<N>& d) {
    const auto* bytes = reinterpret_cast<const char*>(&d);
    for (std::size_t k = 0; k < sizeof(Dop<N>); k += 64) __builtin_prefetch(bytes + k);
    __builtin_prefetch(bytes + sizeof(Dop<N>) - 1);
  }
};

/// Without a contact distance, on the coordinate axes: each feature's boxes at t = 0 and at
/// t = 1, read from the positions (row-major: vertex v at 3 v). Two features meet unless an axis
/// separates them strictly at both ends, the same way round: two linearly moving point sets on the
/// two sides of a fixed direction at t = 0 and at t = 1 stay so in between (the gap is concave in
/// t; docs/culling.md "Apart at both ends in the feature stage"). Swept boxes that miss each other
/// are apart at both ends, so this drops every pair the swept AABBs drop, and more; coordinates
/// are compared as they are, so it is exact.
struct EndPositions {
  /// The two triangles' boxes first: the traversal tested their swept boxes only.
  static constexpr bool kTrianglesFirst = true;
  const double* x0;
  const double* x1;

#if defined(__SSE2__)
  // Two registers per coordinate triple: (x, y) and (z, z).
  struct Point {
    __m128d at0[2], at1[2];
  };
  struct Box {
    __m128d lo0[2], hi0[2], lo1[2], hi1[2];
  };
  [[nodiscard]] Point vertex(std::int32_t v) const {
    const double* p0 = x0 + 3 * at(v);
    const double* p1 = x1 + 3 * at(v);
    return {{_mm_loadu_pd(p0), _mm_load1_pd(p0 + 2)}, {_mm_loadu_pd(p1), _mm_load1_pd(p1 + 2)}};
  }
  [[nodiscard]] static Box hull(std::initializer_list<Point> points) {
    const Point& first = *points.begin();
    Box b{
        {first.at0[0], first.at0[1]},
        {first.at0[0], first.at0[1]},
        {first.at1[0], first.at1[1]},
        {first.at1[0], first.at1[1]}};
    for (const Point& p : points) {
      for (std::size_t r = 0; r < 2; ++r) {
        b.lo0[r] = _mm_min_pd(b.lo0[r], p.at0[r]);
        b.hi0[r] = _mm_max_pd(b.hi0[r], p.at0[r]);
        b.lo1[r] = _mm_min_pd(b.lo1[r], p.at1[r]);
        b.hi1[r] = _mm_max_pd(b.hi1[r], p.at1[r]);
      }
    }
    return b;
  }
  /// Not apart on any axis (NaN compares false: never apart), without branches.
  [[nodiscard]] static bool meet(const Box& a, const Box& b) {
    return meet_as(a.lo0, a.hi0, a.lo1, a.hi1, b);
  }
  [[nodiscard]] static bool meet(const Point& p, const Box& b) {
    return meet_as(p.at0, p.at0, p.at1, p.at1, b);
  }
  /// meet() of the box with these bounds (a point: lo = hi) and b.
  [[nodiscard]] static bool meet_as(
      const __m128d* lo0,
      const __m128d* hi0,
      const __m128d* lo1,
      const __m128d* hi1,
      const Box& b) {
    __m128d apart = _mm_setzero_pd();
    for (std::size_t r = 0; r < 2; ++r) {
      const __m128d below =
          _mm_and_pd(_mm_cmplt_pd(hi0[r], b.lo0[r]), _mm_cmplt_pd(hi1[r], b.lo1[r]));
      const __m128d above =
          _mm_and_pd(_mm_cmplt_pd(b.hi0[r], lo0[r]), _mm_cmplt_pd(b.hi1[r], lo1[r]));
      apart = _mm_or_pd(apart, _mm_or_pd(below, above));
    }
    return _mm_movemask_pd(apart) == 0;
  }
#else
  struct Point {
    std::array<double, 3> at0, at1;
  };
  struct Box {
    std::array<double, 3> lo0, hi0, lo1, hi1;
  };
  [[nodiscard]] Point vertex(std::int32_t v) const {
    Point p;
    for (std::size_t k = 0; k < 3; ++k) {
      p.at0[k] = x0[3 * at(v) + k];
      p.at1[k] = x1[3 * at(v) + k];
    }
    return p;
  }
  [[nodiscard]] static Box hull(std::initializer_list<Point> points) {
    const Point& first = *points.begin();
    Box b{first.at0, first.at0, first.at1, first.at1};
    for (const Point& p : points) {
      for (std::size_t k = 0; k < 3; ++k) {
        b.lo0[k] = std::min(b.lo0[k], p.at0[k]);
        b.hi0[k] = std::max(b.hi0[k], p.at0[k]);
        b.lo1[k] = std::min(b.lo1[k], p.at1[k]);
        b.hi1[k] = std::max(b.hi1[k], p.at1[k]);
      }
    }
    return b;
  }
  [[nodiscard]] static bool meet(const Box& a, const Box& b) {
    bool apart = false;
    for (std::size_t k = 0; k < 3; ++k) {
      apart = apart | ((a.hi0[k] < b.lo0[k]) & (a.hi1[k] < b.lo1[k])) |
              ((b.hi0[k] < a.lo0[k]) & (b.hi1[k] < a.lo1[k]));
    }
    return !apart;
  }
  [[nodiscard]] static bool meet(const Point& p, const Box& b) {
    return meet(Box{p.at0, p.at0, p.at1, p.at1}, b);
  }
#endif
  [[nodiscard]] Box face(std::int32_t, const std::array<std::int32_t, 3>& corners) const {
    return hull({vertex(corners[0]), vertex(corners[1]), vertex(corners[2])});
  }
  [[nodiscard]] Box edge(const std::array<std::int32_t, 2>& ends) const {
    return hull({vertex(ends[0]), vertex(ends[1])});
  }
  /// Asks for the corners' positions at both ends (24 bytes each: up to two cache lines).
  void prefetch(std::int32_t, const std::array<std::int32_t, 3>& corners) const {
    for (const std::int32_t v : corners) {
      for (const double* x : {x0, x1}) {
        __builtin_prefetch(x + 3 * at(v));
        __builtin_prefetch(x + 3 * at(v) + 2);
      }
    }
  }
};

/// Triangle pairs per chunk of the feature stage: a chunk's candidates are written to fixed
/// buffers without branches (a slot is written, then kept or not) and appended at once.
constexpr std::size_t kChunkPairs = 64;

/// Prefetch distances of owned_feature_pairs, in pairs, and the mesh size from which it
/// prefetches (below it the records and volumes it reads stay in the caches).
constexpr std::size_t kFeatureFar = 16;
constexpr std::size_t kFeatureNear = 8;
constexpr std::int32_t kFeaturePrefetchFrom = 16384;

/// The feature stage of ccd_candidates_from_triangle_pairs, with the part-exclusion checks compiled
/// in or out (`kExclusions` = topology.has_exclusions(): without exclusions every *_excluded is
/// false), feature pairs tested on `boxes` (SweptVolumes or EndPositions). Reads one
/// OwnedFeatures record per triangle instead of the owned bits, corners, side edges and their
/// endpoints from four arrays; the pairs, the rules and the order of what is appended are those
/// of the bit-by-bit loop.
template <bool kExclusions, bool kFans, class Boxes>
void owned_feature_pairs(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const Boxes& boxes,
    IntervalFans* fans,
    FeatureCandidates& out,
    std::int64_t& feature_bv_tests,
    std::int64_t& candidate_pairs) {
  using Owned = FeatureTopology::OwnedFeatures;
  // At most 3 + 3 VF and 3 × 3 EE candidates per triangle pair.
  std::array<VertexFacePair, 6 * kChunkPairs> vf;
  std::array<EdgeEdgePair, 9 * kChunkPairs> ee;
  std::size_t num_vf = 0;
  std::size_t num_ee = 0;
  std::int64_t tests = 0;
  // VF pairs of the vertices `owner` owns against face `face`: each slot is written, and kept
  // when the pair is not on a corner of the face and the boxes meet.
  const auto vertices_vs_face =
      [&](const Owned& owner, const Owned& face, std::int32_t f, const auto& face_box) {
        for (std::size_t k = 0; k < owner.num_vertices; ++k) {
          const std::int32_t v = owner.vertices[k];
          bool wanted = !is_corner(v, face.corners);
          if constexpr (kExclusions) wanted = wanted && !topology.vertex_face_excluded(v, f);
          tests += wanted;
          vf[num_vf] = {v, f};
          num_vf += static_cast<std::size_t>(wanted) &
                    static_cast<std::size_t>(Boxes::meet(boxes.vertex(v), face_box));
        }
      };
  const auto flush = [&] {
    out.vf.insert(out.vf.end(), vf.begin(), vf.begin() + static_cast<std::ptrdiff_t>(num_vf));
    out.ee.insert(out.ee.end(), ee.begin(), ee.begin() + static_cast<std::ptrdiff_t>(num_ee));
    num_vf = 0;
    num_ee = 0;
  };
  // The pairs' triangles are scattered over a large mesh: ask for a later pair's owned-feature
  // records kFeatureFar pairs on and its boxes kFeatureNear pairs on (the second triangle's,
  // from its record, by then in the cache: the first triangle of a pair mostly repeats).
  const bool prefetch = topology.num_triangles() >= kFeaturePrefetchFrom;
  const std::size_t num_pairs = pairs.size();
  std::size_t in_chunk = 0;
  for (std::size_t at_pair = 0; at_pair < num_pairs; ++at_pair) {
    if (prefetch && at_pair + kFeatureFar < num_pairs) {
      const TrianglePair& f = pairs[at_pair + kFeatureFar];
      __builtin_prefetch(&topology.owned_features(f.a));
      __builtin_prefetch(&topology.owned_features(f.b));
    }
    if (prefetch && at_pair + kFeatureNear < num_pairs) {
      const TrianglePair& f = pairs[at_pair + kFeatureNear];
      boxes.prefetch(f.b, topology.owned_features(f.b).corners);
    }
    const TrianglePair& p = pairs[at_pair];
    if constexpr (kExclusions) {
      if (topology.owned_pairs_excluded(p.a, p.b)) continue;
    }
    const Owned& a = topology.owned_features(p.a);
    const Owned& b = topology.owned_features(p.b);
    if constexpr (kFans) {
      // A corner both share whose fan is certified over the interval: the two triangles never
      // meet beyond what they share, so no feature pair they own can touch (a candidate pair, as
      // a DCD pair a fan settles, with no feature pairs).
      if (share_certified_corner(a.corners, b.corners, *fans)) {
        ++candidate_pairs;
        continue;
      }
    }
    const auto& face_a = boxes.face(p.a, a.corners);
    const auto& face_b = boxes.face(p.b, b.corners);
    if constexpr (Boxes::kTrianglesFirst) {
      // Triangles apart hold features apart: no pair of theirs can meet, and the pair is culled
      // (not a candidate, as the relative filter's pairs were not).
      if (!Boxes::meet(face_a, face_b)) continue;
    }
    ++candidate_pairs;
    // VF: the vertices each triangle owns against the other triangle's face.
    vertices_vs_face(a, b, p.b, face_b);
    vertices_vs_face(b, a, p.a, face_a);
    // EE: the edges a owns against the edges b owns.
    using EdgeBox = decltype(boxes.edge(a.edge_ends[0]));
    std::array<EdgeBox, 3> edges_b;
    const std::size_t num_edges_b = a.num_edges != 0 ? b.num_edges : 0;  // none needed otherwise
    for (std::size_t j = 0; j < num_edges_b; ++j) edges_b[j] = boxes.edge(b.edge_ends[j]);
    for (std::size_t i = 0; i < a.num_edges; ++i) {
      const std::int32_t ea = a.edges[i];
      const EdgeBox box_a = boxes.edge(a.edge_ends[i]);
      for (std::size_t j = 0; j < b.num_edges; ++j) {
        const std::int32_t eb = b.edges[j];
        bool wanted = !share_endpoint(a.edge_ends[i], b.edge_ends[j]);
        if constexpr (kExclusions) wanted = wanted && !topology.edges_excluded(ea, eb);
        tests += wanted;
        ee[num_ee] = {std::min(ea, eb), std::max(ea, eb)};
        num_ee += static_cast<std::size_t>(wanted) &
                  static_cast<std::size_t>(Boxes::meet(box_a, edges_b[j]));
      }
    }
    if (++in_chunk == kChunkPairs) {
      flush();
      in_chunk = 0;
    }
  }
  flush();
  feature_bv_tests += tests;
}

/// Calls `f` with what the feature stage tests on: the positions at both ends without a contact
/// distance (ends given), else the swept volumes.
template <int N, class F>
void with_boxes(const FeatureBounds<N>& bounds, const IntervalEnds& ends, F&& f) {
  if (ends.x_t0 != nullptr) {
    f(EndPositions{ends.x_t0->data(), ends.x_t1->data()});
  } else {
    f(SweptVolumes<N>{bounds});
  }
}

}  // namespace

template <int N>
void ccd_candidates_from_triangle_pairs(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const FeatureBounds<N>& bounds,
    FeatureCandidates& out,
    Counters& counters,
    IntervalFans* fans,
    const IntervalEnds& ends) {
  std::int64_t feature_bv_tests = 0;
  std::int64_t candidate_pairs = 0;
  with_boxes(bounds, ends, [&](const auto& boxes) {
    const auto run = [&]<bool kExclusions, bool kFans>() {
      owned_feature_pairs<kExclusions, kFans>(
          topology, pairs, boxes, fans, out, feature_bv_tests, candidate_pairs);
    };
    if (topology.has_exclusions()) {
      fans == nullptr ? run.template operator()<true, false>()
                      : run.template operator()<true, true>();
    } else {
      fans == nullptr ? run.template operator()<false, false>()
                      : run.template operator()<false, true>();
    }
  });
  counters.feature_bv_tests += feature_bv_tests;
  counters.candidate_pairs += candidate_pairs;
}

namespace {

/// ccd_candidates_brute_force on `boxes` (SweptVolumes or EndPositions, as the hierarchies').
template <class Boxes>
void brute_feature_pairs(
    const FeatureTopology& topology,
    const Boxes& boxes,
    FeatureCandidates& out,
    std::int64_t& tests,
    IntervalFans* fans) {
  const std::int32_t num_faces = topology.num_triangles();
  const std::int32_t num_vertices = topology.num_vertices();
  const std::int32_t num_edges = topology.num_edges();
  // The fan rule of ccd_candidates_from_triangle_pairs, on the pair of owners a hierarchy would
  // have formed the feature pair from.
  const auto settled = [&](std::int32_t a, std::int32_t b) {
    return fans != nullptr &&
           share_certified_corner(topology.triangle(a), topology.triangle(b), *fans);
  };
  // Every vertex that lies on a triangle against every face it is not a corner of.
  for (std::int32_t v = 0; v < num_vertices; ++v) {
    if (topology.vertex_owner(v) < 0) continue;
    const auto bv = boxes.vertex(v);
    for (std::int32_t f = 0; f < num_faces; ++f) {
      const auto& t = topology.triangle(f);
      if (is_corner(v, t) || topology.vertex_face_excluded(v, f)) continue;
      if (settled(topology.vertex_owner(v), f)) continue;
      ++tests;
      if (Boxes::meet(bv, boxes.face(f, t))) out.vf.push_back({v, f});
    }
  }
  // Every pair of edges a < b without a common endpoint.
  for (std::int32_t a = 0; a < num_edges; ++a) {
    const auto& ends_a = topology.edge(a);
    const auto ba = boxes.edge(ends_a);
    for (std::int32_t b = a + 1; b < num_edges; ++b) {
      if (share_endpoint(ends_a, topology.edge(b)) || topology.edges_excluded(a, b)) continue;
      if (settled(topology.edge_owner(a), topology.edge_owner(b))) continue;
      ++tests;
      if (Boxes::meet(ba, boxes.edge(topology.edge(b)))) out.ee.push_back({a, b});
    }
  }
}

}  // namespace

template <int N>
void ccd_candidates_brute_force(
    const FeatureTopology& topology,
    const FeatureBounds<N>& bounds,
    FeatureCandidates& out,
    Counters& counters,
    IntervalFans* fans,
    const IntervalEnds& ends) {
  std::int64_t tests = 0;
  with_boxes(bounds, ends, [&](const auto& boxes) {
    brute_feature_pairs(topology, boxes, out, tests, fans);
  });
  const std::int32_t num_faces = topology.num_triangles();
  counters.feature_bv_tests += tests;
  counters.candidate_pairs += static_cast<std::int64_t>(num_faces) * (num_faces - 1) / 2;
}

void dcd_filter_triangle_pairs(
    const FeatureTopology& topology, std::vector<TrianglePair>& pairs, Counters& counters) {
  const auto kept = std::remove_if(pairs.begin(), pairs.end(), [&](const TrianglePair& p) {
    return !dcd_checks_pair(topology, p);
  });
  pairs.erase(kept, pairs.end());
  counters.candidate_pairs += static_cast<std::int64_t>(pairs.size());
}

template <int N>
void dcd_candidates_brute_force(
    const FeatureTopology& topology,
    std::span<const Dop<N>> triangle_bounds,
    std::vector<TrianglePair>& out,
    Counters& counters) {
  const std::int32_t num_faces = topology.num_triangles();
  std::int64_t tests = 0;
  for (std::int32_t a = 0; a < num_faces; ++a) {
    const Dop<N>& ba = triangle_bounds[at(a)];
    for (std::int32_t b = a + 1; b < num_faces; ++b) {
      ++tests;
      if (!ba.overlaps(triangle_bounds[at(b)])) continue;
      const TrianglePair p{a, b};
      if (dcd_checks_pair(topology, p)) out.push_back(p);
    }
  }
  counters.bv_tests += tests;
  counters.candidate_pairs += static_cast<std::int64_t>(num_faces) * (num_faces - 1) / 2;
}

template struct FeatureBounds<3>;
template struct FeatureBounds<8>;
template void ccd_candidates_from_triangle_pairs<3>(
    const FeatureTopology&,
    std::span<const TrianglePair>,
    const FeatureBounds<3>&,
    FeatureCandidates&,
    Counters&,
    IntervalFans*,
    const IntervalEnds&);
template void ccd_candidates_from_triangle_pairs<8>(
    const FeatureTopology&,
    std::span<const TrianglePair>,
    const FeatureBounds<8>&,
    FeatureCandidates&,
    Counters&,
    IntervalFans*,
    const IntervalEnds&);
template void ccd_candidates_brute_force<3>(
    const FeatureTopology&,
    const FeatureBounds<3>&,
    FeatureCandidates&,
    Counters&,
    IntervalFans*,
    const IntervalEnds&);
template void ccd_candidates_brute_force<8>(
    const FeatureTopology&,
    const FeatureBounds<8>&,
    FeatureCandidates&,
    Counters&,
    IntervalFans*,
    const IntervalEnds&);
template void dcd_candidates_brute_force<3>(
    const FeatureTopology&, std::span<const Dop<3>>, std::vector<TrianglePair>&, Counters&);
template void dcd_candidates_brute_force<8>(
    const FeatureTopology&, std::span<const Dop<8>>, std::vector<TrianglePair>&, Counters&);

}  // namespace skelcd::culling
