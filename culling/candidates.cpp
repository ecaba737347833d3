#include "culling/candidates.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstring>
#include <initializer_list>
#include <memory>
#include <type_traits>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "ccd/detail/lanes.hpp"
#include "culling/detail/swept_corners.hpp"

#if defined(__x86_64__) && defined(__GNUC__)
#define SKELCD_FEATURE_AVX2 1
// Declares the AVX builtins (its target pragmas) for the AVX2 build's one vptest; nothing here
// calls its intrinsics from code built for the baseline.
#include <immintrin.h>
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

template <int N>
void FeatureBounds<N>::swept_triangles(
    const FeatureTopology& topology,
    const skinning::Positions& x_t0,
    const skinning::Positions& x_t1) {
  // Every axis past the coordinate ones has exactly two non-zero components, each ±1.
  static_assert(N == 3 || N == 8, "the axes below are Dop<3>'s and Dop<8>'s");
  vertices.clear();
  const auto num_faces = static_cast<std::size_t>(topology.num_triangles());
  triangles.resize(num_faces);
  const double* const p0 = x_t0.data();  // row-major: vertex v at p + 3 v
  const double* const p1 = x_t1.data();
  for (std::size_t f = 0; f < num_faces; ++f) {
    const auto& t = topology.triangle(static_cast<std::int32_t>(f));
    std::array<const double*, 6> c{};
    for (std::size_t k = 0; k < 3; ++k) {
      c[2 * k] = p0 + 3 * at(t[k]);
      c[2 * k + 1] = p1 + 3 * at(t[k]);
    }
    detail::swept_corners(c, triangles[f]);
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
  /// A triangle's corners as owned_feature_pairs reads them: here their volumes, in place.
  struct Corners {
    std::array<const Dop<N>*, 3> at;
  };
  [[nodiscard]] Corners corners(const std::array<std::int32_t, 3>& c) const {
    return {{&bounds.vertices[at(c[0])], &bounds.vertices[at(c[1])], &bounds.vertices[at(c[2])]}};
  }
  [[nodiscard]] static const Dop<N>& corner(const Corners& c, std::size_t slot) {
    return *c.at[slot];
  }
  [[nodiscard]] const Dop<N>& face_of(std::int32_t f, const Corners&) const {
    return bounds.triangles[at(f)];
  }
  [[nodiscard]] static Dop<N> edge_of(const Corners& c, const std::array<std::uint8_t, 2>& ends) {
    Dop<N> d = *c.at[ends[0]];
    d.merge(*c.at[ends[1]]);
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
  /// A point set's extents (a vertex, an edge, a face) at both ends on the six face diagonals,
  /// two a register:
  /// (x + y, y + z), (x − y, y − z), (z + x, z − x); z − x as z + (−x), the same rounding.
  struct DiagonalBox {
    __m128d lo0[3], hi0[3], lo1[3], hi1[3];
  };
  /// The extents of the points `ids` (at least one) on the diagonals at both ends.
  [[nodiscard]] DiagonalBox diagonal_box(std::initializer_list<std::int32_t> ids) const {
    const __m128d negate_high = _mm_set_pd(-0.0, 0.0);
    const auto project = [&](const double* p, __m128d* v) {
      const __m128d xy = _mm_loadu_pd(p);
      const __m128d yz = _mm_loadu_pd(p + 1);
      v[0] = _mm_add_pd(xy, yz);
      v[1] = _mm_sub_pd(xy, yz);
      v[2] = _mm_add_pd(_mm_load1_pd(p + 2), _mm_xor_pd(_mm_load1_pd(p), negate_high));
    };
    DiagonalBox b;
    project(x0 + 3 * at(*ids.begin()), b.lo0);
    project(x1 + 3 * at(*ids.begin()), b.lo1);
    for (std::size_t r = 0; r < 3; ++r) {
      b.hi0[r] = b.lo0[r];
      b.hi1[r] = b.lo1[r];
    }
    for (auto id = ids.begin() + 1; id != ids.end(); ++id) {
      DiagonalBox q;
      project(x0 + 3 * at(*id), q.lo0);
      project(x1 + 3 * at(*id), q.lo1);
      for (std::size_t r = 0; r < 3; ++r) {
        q.hi0[r] = q.lo0[r];
        q.hi1[r] = q.lo1[r];
      }
      merge(b, q);
    }
    return b;
  }
  static void merge(DiagonalBox& b, const DiagonalBox& q) {
    for (std::size_t r = 0; r < 3; ++r) {
      b.lo0[r] = _mm_min_pd(b.lo0[r], q.lo0[r]);
      b.hi0[r] = _mm_max_pd(b.hi0[r], q.hi0[r]);
      b.lo1[r] = _mm_min_pd(b.lo1[r], q.lo1[r]);
      b.hi1[r] = _mm_max_pd(b.hi1[r], q.hi1[r]);
    }
  }
  /// Not apart on any face diagonal at both ends (the rounded projections compared: rounding is
  /// monotone, so rounded values strictly apart are exact values strictly apart).
  [[nodiscard]] static bool diagonal_meet(const DiagonalBox& a, const DiagonalBox& b) {
    __m128d apart = _mm_setzero_pd();
    for (std::size_t r = 0; r < 3; ++r) {
      const __m128d below =
          _mm_and_pd(_mm_cmplt_pd(a.hi0[r], b.lo0[r]), _mm_cmplt_pd(a.hi1[r], b.lo1[r]));
      const __m128d above =
          _mm_and_pd(_mm_cmplt_pd(b.hi0[r], a.lo0[r]), _mm_cmplt_pd(b.hi1[r], a.lo1[r]));
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
  struct DiagonalBox {
    std::array<double, 6> lo0, hi0, lo1, hi1;
  };
  [[nodiscard]] DiagonalBox diagonal_box(std::initializer_list<std::int32_t> ids) const {
    const auto project = [](const double* p) {
      return std::array<double, 6>{
          p[0] + p[1], p[1] + p[2], p[0] - p[1], p[1] - p[2], p[2] + p[0], p[2] - p[0]};
    };
    DiagonalBox b;
    b.lo0 = b.hi0 = project(x0 + 3 * at(*ids.begin()));
    b.lo1 = b.hi1 = project(x1 + 3 * at(*ids.begin()));
    for (auto id = ids.begin() + 1; id != ids.end(); ++id) {
      DiagonalBox q;
      q.lo0 = q.hi0 = project(x0 + 3 * at(*id));
      q.lo1 = q.hi1 = project(x1 + 3 * at(*id));
      merge(b, q);
    }
    return b;
  }
  static void merge(DiagonalBox& b, const DiagonalBox& q) {
    for (std::size_t d = 0; d < 6; ++d) {
      b.lo0[d] = std::min(b.lo0[d], q.lo0[d]);
      b.hi0[d] = std::max(b.hi0[d], q.hi0[d]);
      b.lo1[d] = std::min(b.lo1[d], q.lo1[d]);
      b.hi1[d] = std::max(b.hi1[d], q.hi1[d]);
    }
  }
  [[nodiscard]] static bool diagonal_meet(const DiagonalBox& a, const DiagonalBox& b) {
    bool apart = false;
    for (std::size_t d = 0; d < 6; ++d) {
      apart = apart | ((a.hi0[d] < b.lo0[d]) & (a.hi1[d] < b.lo1[d])) |
              ((b.hi0[d] < a.lo0[d]) & (b.hi1[d] < a.lo1[d]));
    }
    return !apart;
  }
#endif
  [[nodiscard]] Box face(std::int32_t, const std::array<std::int32_t, 3>& corners) const {
    return hull({vertex(corners[0]), vertex(corners[1]), vertex(corners[2])});
  }
  [[nodiscard]] Box edge(const std::array<std::int32_t, 2>& ends) const {
    return hull({vertex(ends[0]), vertex(ends[1])});
  }
  /// A triangle's corners as owned_feature_pairs reads them: their positions, read once.
  using Corners = std::array<Point, 3>;
  [[nodiscard]] Corners corners(const std::array<std::int32_t, 3>& c) const {
    return {vertex(c[0]), vertex(c[1]), vertex(c[2])};
  }
  [[nodiscard]] static const Point& corner(const Corners& c, std::size_t slot) { return c[slot]; }
  [[nodiscard]] static Box face_of(std::int32_t, const Corners& c) {
    return hull({c[0], c[1], c[2]});
  }
  [[nodiscard]] static Box edge_of(const Corners& c, const std::array<std::uint8_t, 2>& ends) {
    return hull({c[ends[0]], c[ends[1]]});
  }
  /// The corners' extents on the diagonals (each a point), and those of a vertex, an edge and
  /// the face built from them (owned_feature_pairs).
  using DiagonalCorners = std::array<DiagonalBox, 3>;
  [[nodiscard]] DiagonalCorners diagonal_corners(
      const Corners&, const std::array<std::int32_t, 3>& ids) const {
    return {diagonal_box({ids[0]}), diagonal_box({ids[1]}), diagonal_box({ids[2]})};
  }
  [[nodiscard]] static const DiagonalBox& diagonal_vertex(
      const DiagonalCorners& d, std::size_t slot) {
    return d[slot];
  }
  [[nodiscard]] static DiagonalBox diagonal_edge(
      const DiagonalCorners& d, const std::array<std::uint8_t, 2>& ends) {
    DiagonalBox b = d[ends[0]];
    merge(b, d[ends[1]]);
    return b;
  }
  [[nodiscard]] static DiagonalBox diagonal_face(const DiagonalCorners& d) {
    DiagonalBox b = d[0];
    merge(b, d[1]);
    merge(b, d[2]);
    return b;
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

#if defined(SKELCD_FEATURE_AVX2)
// Four-double vectors pass between the inline members below; where the baseline ABI has no AVX
// they are split, which is what the note is about. Nothing crosses a library boundary.
#pragma GCC diagnostic ignored "-Wpsabi"

using V4 = ccd::detail::Lanes4;
using M4 = std::int64_t __attribute__((vector_size(32)));

/// EndPositions on four-double vectors: a point's coordinates at one end in one vector,
/// (x, y, z, z), and a triangle's face-diagonal projections in two, (x + y, y + z, z + x, z + x)
/// and (x − y, y − z, z − x, z − x) — each the same single rounding as EndPositions', so that
/// both decide every pair alike. Written with GCC's vector extensions and inlined only into
/// owned_feature_pairs_avx2, where each operation is one AVX2 instruction.
template <bool kPacked>
struct EndPositionsWideAs {
  static constexpr bool kTrianglesFirst = true;
  const double* x0;
  const double* x1;
  const double* packed;  ///< PackedEnds::data() when kPacked

  struct Point {
    V4 at0, at1;
  };
  struct Box {
    V4 lo0, hi0, lo1, hi1;
  };
  struct DiagonalBox {
    Box sums, differences;
  };
  [[gnu::always_inline]] static V4 load(const double* p) { return V4{p[0], p[1], p[2], p[2]}; }
  /// minpd and maxpd: the second operand unless the first is below (above) it.
  [[gnu::always_inline]] static V4 min(const V4& a, const V4& b) { return a < b ? a : b; }
  [[gnu::always_inline]] static V4 max(const V4& a, const V4& b) { return a > b ? a : b; }
  [[gnu::always_inline]] [[nodiscard]] Point vertex(std::int32_t v) const {
    if constexpr (kPacked) {
      const double* line = std::assume_aligned<64>(packed + 8 * at(v));
      V4 a, b;
      std::memcpy(&a, line, sizeof a);
      std::memcpy(&b, line + 4, sizeof b);
      return {a, b};
    } else {
      return {load(x0 + 3 * at(v)), load(x1 + 3 * at(v))};
    }
  }
  [[gnu::always_inline]] static void widen(Box& b, const Point& p) {
    b.lo0 = min(b.lo0, p.at0);
    b.hi0 = max(b.hi0, p.at0);
    b.lo1 = min(b.lo1, p.at1);
    b.hi1 = max(b.hi1, p.at1);
  }
  /// Not apart on any lane at both ends (NaN compares false: never apart).
  [[gnu::always_inline]] [[nodiscard]] static bool meet_as(
      const V4& lo0, const V4& hi0, const V4& lo1, const V4& hi1, const Box& b) {
    const M4 apart = ((hi0 < b.lo0) & (hi1 < b.lo1)) | ((b.hi0 < lo0) & (b.hi1 < lo1));
    // No lane set: one vptest. The builtin is expanded in owned_feature_pairs_avx2, the only
    // function this is inlined into (GCC's vector code for "any lane" took six instructions).
    using V4di = long long __attribute__((vector_size(32)));
    return __builtin_ia32_ptestz256(reinterpret_cast<V4di>(apart), reinterpret_cast<V4di>(apart)) !=
           0;
  }
  [[gnu::always_inline]] [[nodiscard]] static bool meet(const Box& a, const Box& b) {
    return meet_as(a.lo0, a.hi0, a.lo1, a.hi1, b);
  }
  [[gnu::always_inline]] [[nodiscard]] static bool meet(const Point& p, const Box& b) {
    return meet_as(p.at0, p.at0, p.at1, p.at1, b);
  }
  /// (y, z, x, x) of (x, y, z, z).
  [[gnu::always_inline]] static V4 rotate(const V4& v) {
    return __builtin_shuffle(v, M4{1, 2, 0, 0});
  }
  using Corners = std::array<Point, 3>;
  [[gnu::always_inline]] [[nodiscard]] Corners corners(const std::array<std::int32_t, 3>& c) const {
    return {vertex(c[0]), vertex(c[1]), vertex(c[2])};
  }
  [[gnu::always_inline]] [[nodiscard]] static const Point& corner(
      const Corners& c, std::size_t slot) {
    return c[slot];
  }
  [[gnu::always_inline]] [[nodiscard]] static Box face_of(std::int32_t, const Corners& c) {
    Box b{c[0].at0, c[0].at0, c[0].at1, c[0].at1};
    widen(b, c[1]);
    widen(b, c[2]);
    return b;
  }
  [[gnu::always_inline]] [[nodiscard]] static Box edge_of(
      const Corners& c, const std::array<std::uint8_t, 2>& ends) {
    const Point& p = c[ends[0]];
    Box b{p.at0, p.at0, p.at1, p.at1};
    widen(b, c[ends[1]]);
    return b;
  }
  [[gnu::always_inline]] [[nodiscard]] static bool diagonal_meet(
      const DiagonalBox& a, const DiagonalBox& b) {
    return meet(a.sums, b.sums) && meet(a.differences, b.differences);
  }
  /// A corner's projections at both ends: (x + y, y + z, z + x, ·) and (x − y, y − z, z − x, ·).
  struct DiagonalPoint {
    Point sums, differences;
  };
  using DiagonalCorners = std::array<DiagonalPoint, 3>;
  [[gnu::always_inline]] [[nodiscard]] static DiagonalCorners diagonal_corners(
      const Corners& c, const std::array<std::int32_t, 3>&) {
    DiagonalCorners d;
    for (std::size_t k = 0; k < 3; ++k) {
      const Point& q = c[k];
      d[k].sums = {q.at0 + rotate(q.at0), q.at1 + rotate(q.at1)};
      d[k].differences = {q.at0 - rotate(q.at0), q.at1 - rotate(q.at1)};
    }
    return d;
  }
  [[gnu::always_inline]] [[nodiscard]] static const DiagonalPoint& diagonal_vertex(
      const DiagonalCorners& d, std::size_t slot) {
    return d[slot];
  }
  [[gnu::always_inline]] static void widen(DiagonalBox& b, const DiagonalPoint& p) {
    widen(b.sums, p.sums);
    widen(b.differences, p.differences);
  }
  [[gnu::always_inline]] [[nodiscard]] static DiagonalBox diagonal_edge(
      const DiagonalCorners& d, const std::array<std::uint8_t, 2>& ends) {
    const DiagonalPoint& p = d[ends[0]];
    DiagonalBox b{
        {p.sums.at0, p.sums.at0, p.sums.at1, p.sums.at1},
        {p.differences.at0, p.differences.at0, p.differences.at1, p.differences.at1}};
    widen(b, d[ends[1]]);
    return b;
  }
  [[gnu::always_inline]] [[nodiscard]] static DiagonalBox diagonal_face(const DiagonalCorners& d) {
    DiagonalBox b = diagonal_edge(d, {0, 1});
    widen(b, d[2]);
    return b;
  }
  [[gnu::always_inline]] [[nodiscard]] static bool diagonal_meet(
      const DiagonalPoint& p, const DiagonalBox& b) {
    return meet(p.sums, b.sums) & meet(p.differences, b.differences);
  }
  [[gnu::always_inline]] void prefetch(
      std::int32_t, const std::array<std::int32_t, 3>& corners) const {
    for (const std::int32_t v : corners) {
      if constexpr (kPacked) {
        __builtin_prefetch(packed + 8 * at(v));
      } else {
        for (const double* x : {x0, x1}) {
          __builtin_prefetch(x + 3 * at(v));
          __builtin_prefetch(x + 3 * at(v) + 2);
        }
      }
    }
  }
};
using EndPositionsWide = EndPositionsWideAs<false>;

std::atomic<detail::FeatureStageBuild> build_forced{detail::FeatureStageBuild::best};

/// The build of the feature stage that runs: the widest this CPU has, unless the tests asked for
/// another (detail::force_feature_stage_build; never one the CPU lacks).
detail::FeatureStageBuild feature_stage_build() {
  using Build = detail::FeatureStageBuild;
  const Build forced = build_forced.load(std::memory_order_relaxed);
  if (forced == Build::baseline || !ccd::detail::cpu_has_avx2()) return Build::baseline;
  if (forced == Build::avx2 || !ccd::detail::cpu_has_avx512vl()) return Build::avx2;
  return Build::avx512;
}
#endif

/// Triangle pairs per chunk of the feature stage: a chunk's candidates are written to fixed
/// buffers without branches (a slot is written, then kept or not) and appended at once.
constexpr std::size_t kChunkPairs = 64;

/// owned_feature_pairs' VF slot records: the vertex is the second triangle's.
constexpr unsigned kOwnedByB = 4;

/// Prefetch distances of owned_feature_pairs, in pairs, and the mesh size from which it
/// prefetches (below it the records and volumes it reads stay in the caches).
constexpr std::size_t kFeatureFar = 16;
constexpr std::size_t kFeatureNear = 8;
constexpr std::int32_t kFeaturePrefetchFrom = 16384;

/// The corners two triangles share, from one comparison of their ids (a degenerate triangle may
/// list one twice): `bits`, bit 3 i + j when corner i of a is corner j of b; `a_on_b`, bit i when
/// a's corner i is a corner of b; `b_on_a`, bit j when b's corner j is a corner of a.
struct SharedCorners {
  unsigned bits = 0;
  unsigned a_on_b = 0;
  unsigned b_on_a = 0;
};

/// Of SharedCorners::bits: those of a's corner i (its row) and of b's corner j (its column).
constexpr unsigned row_bits(unsigned i) { return 7u << (3 * i); }
constexpr unsigned column_bits(unsigned j) { return 0x49u << j; }

[[gnu::always_inline]] inline SharedCorners shared_corners(
    const FeatureTopology::OwnedFeatures& a, const FeatureTopology::OwnedFeatures& b) {
  SharedCorners s;
#if defined(__SSE2__)
  // Sixteen bytes from each record: the corners and, in the last lane, the first owned vertex
  // (the next member), which the masks leave out.
  static_assert(offsetof(FeatureTopology::OwnedFeatures, vertices) == 12);
  const __m128i ca = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&a));
  const __m128i cb = _mm_loadu_si128(reinterpret_cast<const __m128i*>(&b));
  const auto lanes = [](__m128i m) __attribute__((always_inline)) {
    return static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(m))) & 7u;
  };
  const unsigned row0 = lanes(_mm_cmpeq_epi32(_mm_shuffle_epi32(ca, 0x00), cb));
  const unsigned row1 = lanes(_mm_cmpeq_epi32(_mm_shuffle_epi32(ca, 0x55), cb));
  const unsigned row2 = lanes(_mm_cmpeq_epi32(_mm_shuffle_epi32(ca, 0xAA), cb));
  s.bits = row0 | row1 << 3 | row2 << 6;
  s.b_on_a = row0 | row1 | row2;
  s.a_on_b = lanes(_mm_or_si128(
      _mm_or_si128(
          _mm_cmpeq_epi32(ca, _mm_shuffle_epi32(cb, 0x00)),
          _mm_cmpeq_epi32(ca, _mm_shuffle_epi32(cb, 0x55))),
      _mm_cmpeq_epi32(ca, _mm_shuffle_epi32(cb, 0xAA))));
#else
  for (unsigned i = 0; i < 3; ++i) {
    for (unsigned j = 0; j < 3; ++j) {
      if (a.corners[i] == b.corners[j]) {
        s.bits |= 1u << (3 * i + j);
        s.a_on_b |= 1u << i;
        s.b_on_a |= 1u << j;
      }
    }
  }
#endif
  return s;
}

/// owned_feature_pairs' VF pairs of the vertices `owner` owns (its corners' positions or
/// volumes `corners`) against face `f` (volume `face_box`): each slot is written, and kept when
/// the vertex is not a corner of the face (`on_face`: bit s when owner's corner s is) and the
/// boxes meet. `slots` gets, beside each slot, the vertex's corner slot | `tag` (kOwnedByB for
/// the second triangle's), for the diagonal test that follows.
template <bool kExclusions, class Boxes, class FaceBox>
[[gnu::always_inline]] inline void vertices_vs_face(
    const FeatureTopology& topology,
    const FeatureTopology::OwnedFeatures& owner,
    const typename Boxes::Corners& corners,
    unsigned on_face,
    std::int32_t f,
    const FaceBox& face_box,
    VertexFacePair* vf,
    std::uint8_t* slots,
    unsigned tag,
    std::size_t& num_vf,
    std::int64_t& tests) {
  for (std::size_t k = 0; k < owner.num_vertices; ++k) {
    const std::int32_t v = owner.vertices[k];
    const unsigned slot = owner.vertex_slots[k];
    bool wanted = ((on_face >> slot) & 1u) == 0;
    if constexpr (kExclusions) wanted = wanted && !topology.vertex_face_excluded(v, f);
    tests += wanted;
    vf[num_vf] = {v, f};
    slots[num_vf] = static_cast<std::uint8_t>(tag | slot);
    num_vf += static_cast<std::size_t>(wanted) &
              static_cast<std::size_t>(Boxes::meet(Boxes::corner(corners, slot), face_box));
  }
}

/// What owned_feature_pairs holds of two triangles' face diagonals: nothing (a placeholder) where
/// `Boxes` tests no triangles first.
template <class Boxes, bool = Boxes::kTrianglesFirst>
struct DiagonalsOf {
  using Corners = char;
  using Box = char;
};
template <class Boxes>
struct DiagonalsOf<Boxes, true> {
  using Corners = typename Boxes::DiagonalCorners;
  using Box = typename Boxes::DiagonalBox;
};

/// The feature stage of ccd_candidates_from_triangle_pairs, with the part-exclusion checks compiled
/// in or out (`kExclusions` = topology.has_exclusions(): without exclusions every *_excluded is
/// false), feature pairs tested on `boxes` (SweptVolumes, EndPositions or EndPositionsWide).
/// Reads one OwnedFeatures record per triangle, each corner's position (or volume) once, and
/// compares the two triangles' corner ids once (shared_corners) for every "is a corner of" and
/// "share an endpoint" rule; the pairs, the rules and the order of what is appended are those of
/// the bit-by-bit loop, less the feature pairs apart on a face diagonal at both ends
/// (docs/culling.md, "The triangles on the face diagonals", "Each feature pair on the
/// diagonals"). Inlined into each caller, so
/// that owned_feature_pairs_avx2 is built for AVX2 whole.
template <bool kExclusions, bool kFans, class Boxes>
[[gnu::always_inline]] inline void owned_feature_pairs(
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
  // Where each candidate's features are: VF, the vertex's corner slot (| kOwnedByB when the
  // vertex is b's); EE, the two edges' indices among the owned ones (4 i + j).
  std::array<std::uint8_t, 6 * kChunkPairs> vf_slot;
  std::array<std::uint8_t, 9 * kChunkPairs> ee_slots;
  std::size_t num_vf = 0;
  std::size_t num_ee = 0;
  std::int64_t tests = 0;
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
    const SharedCorners shared = shared_corners(a, b);
    if constexpr (kFans) {
      // A corner both share whose fan is certified over the interval: the two triangles never
      // meet beyond what they share, so no feature pair they own can touch (a candidate pair, as
      // a DCD pair a fan settles, with no feature pairs).
      bool settled = false;
      for (unsigned m = shared.a_on_b; m != 0 && !settled; m &= m - 1) {
        settled = fans->certified(a.corners[static_cast<std::size_t>(std::countr_zero(m))]);
      }
      if (settled) {
        ++candidate_pairs;
        continue;
      }
    }
    const auto corners_a = boxes.corners(a.corners);
    const auto corners_b = boxes.corners(b.corners);
    const auto& face_a = boxes.face_of(p.a, corners_a);
    const auto& face_b = boxes.face_of(p.b, corners_b);
    if constexpr (Boxes::kTrianglesFirst) {
      // Triangles apart hold features apart: no pair of theirs can meet, and the pair is culled
      // (not a candidate, as the relative filter's pairs were not).
      if (!Boxes::meet(face_a, face_b)) continue;
    }
    ++candidate_pairs;
    // Neither triangle owns a vertex and one owns no edge: no feature pair to test (a twelfth of
    // the candidates on the cloth-ball step, an eighth on BCN_Epileptic).
    if (a.num_vertices == 0 && b.num_vertices == 0 && (a.num_edges == 0 || b.num_edges == 0)) {
      continue;
    }
    // The two triangles apart on a face diagonal at both ends hold every pair of their features
    // apart (the axes' argument along a fixed direction; rounded projections strictly apart are
    // exact ones strictly apart): a candidate with no feature pairs, dropped before any feature
    // pair is tested.
    [[maybe_unused]] typename DiagonalsOf<Boxes>::Corners diagonals_a{}, diagonals_b{};
    [[maybe_unused]] typename DiagonalsOf<Boxes>::Box diagonal_face_a{}, diagonal_face_b{};
    if constexpr (Boxes::kTrianglesFirst) {
      diagonals_a = boxes.diagonal_corners(corners_a, a.corners);
      diagonals_b = boxes.diagonal_corners(corners_b, b.corners);
      diagonal_face_a = Boxes::diagonal_face(diagonals_a);
      diagonal_face_b = Boxes::diagonal_face(diagonals_b);
      if (!Boxes::diagonal_meet(diagonal_face_a, diagonal_face_b)) continue;
    }
    const std::size_t vf_before = num_vf;
    const std::size_t ee_before = num_ee;
    // VF: the vertices each triangle owns against the other triangle's face.
    vertices_vs_face<kExclusions, Boxes>(
        topology,
        a,
        corners_a,
        shared.a_on_b,
        p.b,
        face_b,
        vf.data(),
        vf_slot.data(),
        0u,
        num_vf,
        tests);
    vertices_vs_face<kExclusions, Boxes>(
        topology,
        b,
        corners_b,
        shared.b_on_a,
        p.a,
        face_a,
        vf.data(),
        vf_slot.data(),
        kOwnedByB,
        num_vf,
        tests);
    // EE: the edges a owns against the edges b owns; two share an endpoint when shared.bits has
    // a bit in the rows of a's ends and the columns of b's.
    using EdgeBox = decltype(Boxes::edge_of(corners_a, a.edge_slots[0]));
    std::array<EdgeBox, 3> edges_b;
    std::array<unsigned, 3> columns_b;
    const std::size_t num_edges_b = a.num_edges != 0 ? b.num_edges : 0;  // none needed otherwise
    for (std::size_t j = 0; j < num_edges_b; ++j) {
      edges_b[j] = Boxes::edge_of(corners_b, b.edge_slots[j]);
      columns_b[j] = column_bits(b.edge_slots[j][0]) | column_bits(b.edge_slots[j][1]);
    }
    for (std::size_t i = 0; i < a.num_edges; ++i) {
      const std::int32_t ea = a.edges[i];
      const EdgeBox box_a = Boxes::edge_of(corners_a, a.edge_slots[i]);
      const unsigned rows_a =
          shared.bits & (row_bits(a.edge_slots[i][0]) | row_bits(a.edge_slots[i][1]));
      for (std::size_t j = 0; j < b.num_edges; ++j) {
        const std::int32_t eb = b.edges[j];
        bool wanted = (rows_a & columns_b[j]) == 0;
        if constexpr (kExclusions) wanted = wanted && !topology.edges_excluded(ea, eb);
        tests += wanted;
        ee[num_ee] = {std::min(ea, eb), std::max(ea, eb)};
        ee_slots[num_ee] = static_cast<std::uint8_t>(i << 2 | j);
        num_ee += static_cast<std::size_t>(wanted) &
                  static_cast<std::size_t>(Boxes::meet(box_a, edges_b[j]));
      }
    }
    // Feature pairs kept, apart on a face diagonal at both ends: none of them can touch (the
    // axes' argument along a fixed direction, as for the two triangles above). Dropped again.
    if constexpr (Boxes::kTrianglesFirst) {
      std::size_t kept = vf_before;
      for (std::size_t r = vf_before; r < num_vf; ++r) {
        const unsigned d = vf_slot[r];
        const bool meet =
            (d & kOwnedByB) != 0
                ? Boxes::diagonal_meet(Boxes::diagonal_vertex(diagonals_b, d & 3u), diagonal_face_a)
                : Boxes::diagonal_meet(
                      Boxes::diagonal_vertex(diagonals_a, d & 3u), diagonal_face_b);
        vf[kept] = vf[r];
        kept += static_cast<std::size_t>(meet);
      }
      num_vf = kept;
      kept = ee_before;
      for (std::size_t r = ee_before; r < num_ee; ++r) {
        const unsigned d = ee_slots[r];
        const bool meet = Boxes::diagonal_meet(
            Boxes::diagonal_edge(diagonals_a, a.edge_slots[d >> 2]),
            Boxes::diagonal_edge(diagonals_b, b.edge_slots[d & 3u]));
        ee[kept] = ee[r];
        kept += static_cast<std::size_t>(meet);
      }
      num_ee = kept;
    }
    if (++in_chunk == kChunkPairs) {
      flush();
      in_chunk = 0;
    }
  }
  flush();
  feature_bv_tests += tests;
}

#if defined(SKELCD_FEATURE_AVX2)
/// owned_feature_pairs built for AVX2 (EndPositionsWide): the same pairs, rules and order.
template <bool kExclusions, bool kFans, bool kPacked>
[[gnu::target("avx2")]] void owned_feature_pairs_avx2(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const EndPositionsWideAs<kPacked>& boxes,
    IntervalFans* fans,
    FeatureCandidates& out,
    std::int64_t& feature_bv_tests,
    std::int64_t& candidate_pairs) {
  owned_feature_pairs<kExclusions, kFans>(
      topology, pairs, boxes, fans, out, feature_bv_tests, candidate_pairs);
}

/// The same code built where AVX-512 VL is there: the same four-double operations (IEEE, no
/// contraction: the same bits), with 32 vector registers instead of 16 — the AVX2 build spilled
/// to the stack about a third of its instructions' operands (323 of 1,042 instructions addressed
/// the stack, against 231 of 1,000 here).
template <bool kExclusions, bool kFans, bool kPacked>
[[gnu::target("avx2,avx512f,avx512vl,avx512dq")]] void owned_feature_pairs_avx512(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const EndPositionsWideAs<kPacked>& boxes,
    IntervalFans* fans,
    FeatureCandidates& out,
    std::int64_t& feature_bv_tests,
    std::int64_t& candidate_pairs) {
  owned_feature_pairs<kExclusions, kFans>(
      topology, pairs, boxes, fans, out, feature_bv_tests, candidate_pairs);
}
#endif

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
#if defined(SKELCD_FEATURE_AVX2)
      if constexpr (std::is_same_v<std::decay_t<decltype(boxes)>, EndPositions>) {
        const detail::FeatureStageBuild build = feature_stage_build();
        if (build != detail::FeatureStageBuild::baseline) {
          const auto wide = [&]<bool kPacked>(const EndPositionsWideAs<kPacked>& w) {
            if (build == detail::FeatureStageBuild::avx512) {
              owned_feature_pairs_avx512<kExclusions, kFans, kPacked>(
                  topology, pairs, w, fans, out, feature_bv_tests, candidate_pairs);
            } else {
              owned_feature_pairs_avx2<kExclusions, kFans, kPacked>(
                  topology, pairs, w, fans, out, feature_bv_tests, candidate_pairs);
            }
          };
          if (ends.packed != nullptr) {
            wide(EndPositionsWideAs<true>{boxes.x0, boxes.x1, ends.packed});
          } else {
            wide(EndPositionsWide{boxes.x0, boxes.x1, nullptr});
          }
          return;
        }
      }
#endif
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
  // The face-diagonal rule of ccd_candidates_from_triangle_pairs: features apart on a face
  // diagonal at both ends are tested but not kept. (Its triangles-first shortcuts need no
  // counterpart: triangles apart hold their features apart, which the feature tests find.)
  const auto diagonal_apart = [&](std::initializer_list<std::int32_t> p,
                                  std::initializer_list<std::int32_t> q) {
    if constexpr (Boxes::kTrianglesFirst) {
      return !Boxes::diagonal_meet(boxes.diagonal_box(p), boxes.diagonal_box(q));
    } else {
      return false;
    }
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
      if (Boxes::meet(bv, boxes.face(f, t)) && !diagonal_apart({v}, {t[0], t[1], t[2]}))
        out.vf.push_back({v, f});
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
      const auto& ends_b = topology.edge(b);
      if (Boxes::meet(ba, boxes.edge(ends_b)) &&
          !diagonal_apart({ends_a[0], ends_a[1]}, {ends_b[0], ends_b[1]}))
        out.ee.push_back({a, b});
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

bool feature_stage_reads_packed_ends() {
#if defined(SKELCD_FEATURE_AVX2)
  return feature_stage_build() != detail::FeatureStageBuild::baseline;
#else
  return false;
#endif
}

void PackedEnds::pack(const skinning::Positions& x_t0, const skinning::Positions& x_t1) {
  const auto n = static_cast<std::size_t>(x_t0.rows());
  lines_.resize(n);
  const double* a = x_t0.data();
  const double* b = x_t1.data();
  for (std::size_t v = 0; v < n; ++v) {
    double* line = lines_[v].v;
    line[0] = a[3 * v];
    line[1] = a[3 * v + 1];
    line[2] = line[3] = a[3 * v + 2];
    line[4] = b[3 * v];
    line[5] = b[3 * v + 1];
    line[6] = line[7] = b[3 * v + 2];
  }
}

namespace detail {

void force_feature_stage_build(FeatureStageBuild build) {
#if defined(SKELCD_FEATURE_AVX2)
  build_forced.store(build, std::memory_order_relaxed);
#else
  (void)build;
#endif
}

}  // namespace detail

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
