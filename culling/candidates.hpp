#pragma once
// The feature stage: from triangle pairs (or from nothing, by brute force) to the VF / EE feature
// pairs (CCD) or triangle pairs (DCD) that go to the elementary tests. Every method shares these
// rules, so methods differ only in which triangle pairs they hand over:
// - a VF pair whose vertex is a corner of the face, an EE pair whose edges share an endpoint, and
//   a triangle with itself are never tested; no pair is excluded by distance;
// - part exclusions as in FeatureTopology;
// - with a contact distance, a feature pair is tested only when its features' volumes (of the
//   interval, grown by half of it) overlap; without one, only when no coordinate axis separates
//   its two triangles and then its features at both ends of the interval (IntervalEnds), which
//   drops every pair the swept AABBs drop, and more.
// CCD de-duplication (docs/culling.md has the proof): candidate triangle pair {A, B} produces
// (vertex owned by A, face B), (vertex owned by B, face A) and (edge owned by A, edge owned by B).
// A feature's volume lies inside its owner's, so a feature pair whose volumes overlap always has
// its owner pair among the overlapping triangle pairs, and {owner, face} / {owner, owner} is one
// pair only: each feature pair is produced at most once and never missed. Adjacent triangle pairs
// are therefore *not* skipped for CCD: only their feature pairs that share a vertex are.

#include <compare>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "culling/dop.hpp"
#include "culling/feature_topology.hpp"
#include "culling/frame_result.hpp"
#include "skinning/mesh.hpp"

namespace skelcd::culling {

/// A vertex-face pair: welded vertex `vertex`, triangle `face`.
struct VertexFacePair {
  std::int32_t vertex = -1;
  std::int32_t face = -1;
  friend auto operator<=>(const VertexFacePair&, const VertexFacePair&) = default;
};

/// An edge-edge pair: edge ids a < b.
struct EdgeEdgePair {
  std::int32_t a = -1;
  std::int32_t b = -1;
  friend auto operator<=>(const EdgeEdgePair&, const EdgeEdgePair&) = default;
};

/// Feature pairs of one interval, in the order they were produced (not sorted).
struct FeatureCandidates {
  std::vector<VertexFacePair> vf;
  std::vector<EdgeEdgePair> ee;
  void clear() {
    vf.clear();
    ee.clear();
  }
};

/// The per-interval volumes of every feature of a mesh: vertices (#W), edges (#E), triangles (#F).
/// Edges and triangles are unions of their vertices' volumes (bit-for-bit inside their owners').
template <int N>
struct FeatureBounds {
  std::vector<Dop<N>> vertices;
  std::vector<Dop<N>> edges;
  std::vector<Dop<N>> triangles;

  /// Fills triangles (and edges, unless with_edges is false) from `vertices`. DCD needs no edge
  /// volumes, nor does ccd_candidates_from_triangle_pairs (it forms them from the vertices', and
  /// so the hierarchy methods and the radial view ask for none); brute force and the scenes'
  /// inter-object checks (PairChecker) read them. Allocation-free once the vectors have their
  /// sizes.
  void derive(const FeatureTopology& topology, bool with_edges = true);
  /// triangles = each triangle's static volume at x, bit for bit what static_vertex_bounds(x,
  /// vertices) then derive(topology, false) give, read from the corners' positions directly: the
  /// DCD needs no vertex volumes. `vertices` is cleared (its capacity kept).
  void static_triangles(const FeatureTopology& topology, const skinning::Positions& x);
  /// triangles = a volume of each triangle's linear motion from x_t0 to x_t1 (no contact
  /// distance), read from the six corner positions directly, so that no #W vertex volumes are
  /// held (bounded memory: 128 bytes a vertex for the 16-DOP). The coordinate slabs are those
  /// of derive(); a diagonal slab is the rounded sums' range moved one ulp outwards, which holds
  /// the exact sums (round to nearest errs by at most half an ulp) and may be one ulp wider than
  /// derive()'s. Only for a feature stage that reads the interval's ends instead of the vertex
  /// volumes (feature_stage_tests_ends): `vertices` is cleared (its capacity kept).
  void swept_triangles(
      const FeatureTopology& topology,
      const skinning::Positions& x_t0,
      const skinning::Positions& x_t1);
};

/// Vertex fans over one CCD query's interval (VertexFans::certified_over), each decided the first
/// time a pair asks (a query may bring few pairs). Reused across queries: start() clears.
struct IntervalFans {
  const VertexFans* fans = nullptr;
  const skinning::Positions* x_t0 = nullptr;
  const skinning::Positions* x_t1 = nullptr;
  std::vector<std::uint8_t> state;  ///< per welded vertex: 0 undecided, 1 certified, 2 refused

  void start(
      const VertexFans& of,
      const skinning::Positions& from,
      const skinning::Positions& to,
      std::int32_t num_vertices) {
    fans = &of;
    x_t0 = &from;
    x_t1 = &to;
    state.assign(static_cast<std::size_t>(num_vertices), 0);
  }
  [[nodiscard]] bool certified(std::int32_t v) {
    std::uint8_t& s = state[static_cast<std::size_t>(v)];
    if (s == 0) s = fans->certified_over(*x_t0, *x_t1, v) ? 1 : 2;
    return s == 1;
  }
  /// Decides every vertex now; `flags` (resized) is 1 where certified, else 0 (FanSieve's form).
  void certify_all(std::vector<std::uint8_t>& flags) {
    flags.resize(state.size());
    for (std::size_t v = 0; v < state.size(); ++v) {
      flags[v] = static_cast<std::uint8_t>(certified(static_cast<std::int32_t>(v)));
    }
  }
};

/// The positions at the two ends of a CCD interval, for the feature stage without a contact
/// distance: a triangle pair, then each feature pair, is dropped when a coordinate axis separates
/// the two strictly at t = 0 and at t = 1, the same way round (they never touch in between), in
/// place of the swept volumes' test (AABB or 16-DOP: the 16-DOP's diagonals reject little that
/// this does not, and its volumes cost loads; measured in docs/benchmarks.md).
struct IntervalEnds {
  const skinning::Positions* x_t0 = nullptr;
  const skinning::Positions* x_t1 = nullptr;
  /// Optional: the same positions as PackedEnds::pack lays them out (PackedEnds::data), which
  /// the feature stage's AVX2 build then reads instead (one aligned cache line per vertex).
  const double* packed = nullptr;
};

/// Both ends of every vertex in one 64-byte line, as the feature stage's AVX2 build loads them:
/// vertex v's (x, y, z, z) at t0 in doubles 8 v … 8 v + 3 and at t1 in 8 v + 4 … 8 v + 7. The
/// stage then reads a corner with two aligned loads from one line where the positions' rows take
/// two loads and a shuffle each from up to four lines. Written once per interval by the methods
/// (PairBlocks::start_ccd); 64 bytes a vertex.
class PackedEnds {
 public:
  /// Lays out x_t0 and x_t1 (#W × 3 each, the same rows).
  void pack(const skinning::Positions& x_t0, const skinning::Positions& x_t1);
  [[nodiscard]] const double* data() const { return lines_.empty() ? nullptr : lines_.front().v; }

 private:
  struct alignas(64) Line {
    double v[8];
  };
  std::vector<Line> lines_;
};

/// Whether the feature stage reads IntervalEnds::packed when given: its AVX2 build runs (this
/// CPU has AVX2 and the tests have not forced the baseline build).
[[nodiscard]] bool feature_stage_reads_packed_ends();

/// Meshes from this many triangles on get their ends packed (PairBlocks::start_ccd): below it
/// the positions stay in the caches, and packing cost time (cloth-funnel, 18k triangles, 0.99×)
/// and 64 bytes a vertex.
inline constexpr std::int32_t kPackedEndsFrom = 32768;

/// True when the feature stage tests at both ends (no contact distance): its first test of a
/// triangle pair is then the relative pair filters' (RelativeAabbFilter), so a method runs those
/// only when this is false.
[[nodiscard]] inline bool feature_stage_tests_ends(double min_separation) {
  return min_separation == 0.0;
}

/// IntervalEnds{&x_t0, &x_t1} when feature_stage_tests_ends, else none (the swept volumes, grown
/// by half the contact distance, are tested).
[[nodiscard]] inline IntervalEnds interval_ends(
    double min_separation, const skinning::Positions& x_t0, const skinning::Positions& x_t1) {
  return feature_stage_tests_ends(min_separation) ? IntervalEnds{&x_t0, &x_t1} : IntervalEnds{};
}

/// Triangle pairs per CCD block: the hierarchy methods turn their traversal's pairs into feature
/// candidates and test them a block at a time, so that what they hold at once (pairs, at most 15
/// feature candidates each, the tests' outcomes: a few MB) is bounded whatever the motion, and a
/// block is still long enough to be split over the threads. The feature de-duplication is by
/// ownership within each triangle pair, so blocks never repeat a test.
inline constexpr std::size_t kCcdBlockPairs = std::size_t{1} << 15;

/// CCD feature stage of a hierarchy method: appends the feature pairs of each triangle pair in
/// `pairs` (any order within a pair) to `out`. Reads bounds.vertices and bounds.triangles only:
/// an edge's volume is formed as the union of its endpoints' (bit for bit what derive() stores),
/// so the caller need not hold #E edge volumes.
/// Counts counters.candidate_pairs (triangle pairs not wholly part-excluded, less those the ends
/// test below finds apart) and counters.feature_bv_tests.
/// `fans`: when not null, the query's fans over its interval: a triangle pair sharing a certified
/// corner is a candidate with no feature pairs — none of them can come into contact
/// (docs/culling.md, "Vertex fans over an interval").
/// `ends` (interval_ends): when given, the positions at both ends are read instead of
/// `bounds`: the two triangles are tested first, then each feature pair (IntervalEnds), and the
/// feature pairs a triangle pair kept are dropped again when a face diagonal (x ± y, y ± z,
/// z ± x) separates the two features at both ends (counted as tested; docs/culling.md, "The
/// triangles on the face diagonals", "Each feature pair on the diagonals").
template <int N>
void ccd_candidates_from_triangle_pairs(
    const FeatureTopology& topology,
    std::span<const TrianglePair> pairs,
    const FeatureBounds<N>& bounds,
    FeatureCandidates& out,
    Counters& counters,
    IntervalFans* fans = nullptr,
    const IntervalEnds& ends = {});

namespace detail {
/// The builds of ccd_candidates_from_triangle_pairs' feature stage: `best` is the widest the CPU
/// has (AVX-512 VL, else AVX2, else the baseline SSE2 one); all give the same pairs in the same
/// order, with the same counters.
enum class FeatureStageBuild { best, baseline, avx2, avx512 };
/// For the tests: run `build` (or the widest below it that the CPU has) until asked again;
/// `best` lets it choose again.
void force_feature_stage_build(FeatureStageBuild build);
}  // namespace detail

/// CCD brute force: appends every VF pair (vertex on some triangle × triangle) and EE pair
/// (a < b) that passes the rules above — O(#W·#F + #E²) volume tests, no hierarchy.
/// Counts counters.feature_bv_tests; sets counters.candidate_pairs to #F·(#F−1)/2 (every
/// triangle pair is a candidate of brute force).
/// `fans` as for ccd_candidates_from_triangle_pairs: a feature pair whose owners (vertex_owner,
/// edge_owner) share a certified corner is skipped, as the hierarchy methods skip their pair.
/// `ends` as for ccd_candidates_from_triangle_pairs (each feature pair on the axes, then on the
/// diagonals: the same pairs result).
template <int N>
void ccd_candidates_brute_force(
    const FeatureTopology& topology,
    const FeatureBounds<N>& bounds,
    FeatureCandidates& out,
    Counters& counters,
    IntervalFans* fans = nullptr,
    const IntervalEnds& ends = {});

/// The DCD rules for one triangle pair: not part-excluded, not a duplicate face (the same three
/// welded vertices). Pairs sharing one or two vertices are checked: the exact test handles them.
[[nodiscard]] inline bool dcd_checks_pair(const FeatureTopology& topology, const TrianglePair& p) {
  if (topology.triangles_excluded(p.a, p.b)) return false;
  int shared = 0;
  (void)topology.shared_corners(p.a, p.b, shared);
  return shared < 3;
}

/// DCD feature stage: keeps (in place, order kept) the triangle pairs to test: drops
/// part-excluded pairs and pairs of triangles on the same three welded vertices (duplicate
/// faces). Pairs sharing one or two vertices stay: the exact test handles them. Counts
/// counters.candidate_pairs (pairs kept).
void dcd_filter_triangle_pairs(
    const FeatureTopology& topology, std::vector<TrianglePair>& pairs, Counters& counters);

/// DCD brute force: appends every pair a < b whose triangle volumes overlap (counted in
/// counters.bv_tests), then filters as dcd_filter_triangle_pairs except that candidate_pairs is
/// set to #F·(#F−1)/2.
template <int N>
void dcd_candidates_brute_force(
    const FeatureTopology& topology,
    std::span<const Dop<N>> triangle_bounds,
    std::vector<TrianglePair>& out,
    Counters& counters);

}  // namespace skelcd::culling
