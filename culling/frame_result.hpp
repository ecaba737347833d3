#pragma once
// What one interval (CCD) or one instant (DCD) produces: contacts in welded numbering, counters and
// stage timings — the same for every culling method so methods compare on equal terms.

#include <algorithm>
#include <compare>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace skelcd::culling {

/// The work counters of one row, one entry each: every place that stores, sums, logs, reads or
/// shows them is generated from this list (X(name, meaning)) — the struct below, `+=`, the log's
/// /frames columns (tools/io/log/detail/hdf5_schema.hpp), the log reader, `inspect --frames` and
/// the Python module's arrays. Add a counter here and everywhere follows (docs/architecture.md).
#define SKELCD_COUNTERS(X)                                                              \
  X(atomic_clusters, "atomic clusters (radial-view methods)")                           \
  X(mega_clusters, "mega clusters after merging (dynamic)")                             \
  X(h_minus, "triangles in H- (radial-view methods)")                                   \
  X(h_uncertain, "triangles in Hu (radial-view methods)")                               \
  X(bv_tests, "bounding-volume overlap tests")                                          \
  X(candidate_pairs, "candidate triangle pairs reaching the feature stage")             \
  X(vf_tests, "vertex-face elementary tests")                                           \
  X(ee_tests, "edge-edge elementary tests")                                             \
  X(vf_contacts, "vertex-face contacts")                                                \
  X(ee_contacts, "edge-edge contacts")                                                  \
  X(tt_tests, "triangle-triangle DCD tests")                                            \
  X(dcd_pairs, "intersecting triangle pairs found by DCD")                              \
  X(feature_bv_tests, "feature-pair volume tests before the elementary tests (VF, EE)") \
  X(new_dcd_pairs, "DCD pairs neither in the baseline nor allowed (events)")            \
  X(new_ccd_contacts, "CCD contacts neither in the baseline nor allowed (events)")      \
  X(baseline_dcd_pairs, "DCD pairs the baseline already had")                           \
  X(baseline_ccd_contacts, "CCD contacts within the baseline's regions")                \
  X(allowed_dcd_pairs, "DCD pairs between allowed parts or bones")                      \
  X(allowed_ccd_contacts, "CCD contacts between allowed parts or bones")

/// Microseconds per stage of one row, likewise (X(name, meaning)).
#define SKELCD_STAGE_TIMES(X)                       \
  X(skin_us, "posing the sample(s)")                \
  X(refit_us, "refitting bounding volumes")         \
  X(classify_us, "orientation classes")             \
  X(merge_us, "mega-cluster merging")               \
  X(traverse_us, "hierarchy traversal and filters") \
  X(elementary_us, "elementary tests")

/// Work counters of one interval; every method fills the ones it uses and leaves the rest 0.
struct Counters {
#define SKELCD_COUNTER_MEMBER(name, meaning) std::int64_t name = 0;
  SKELCD_COUNTERS(SKELCD_COUNTER_MEMBER)
#undef SKELCD_COUNTER_MEMBER

  Counters& operator+=(const Counters& other) {
#define SKELCD_COUNTER_ADD(name, meaning) name += other.name;
    SKELCD_COUNTERS(SKELCD_COUNTER_ADD)
#undef SKELCD_COUNTER_ADD
    return *this;
  }
};

/// Microseconds spent per stage in one interval.
struct StageTimes {
#define SKELCD_STAGE_MEMBER(name, meaning) double name = 0;
  SKELCD_STAGE_TIMES(SKELCD_STAGE_MEMBER)
#undef SKELCD_STAGE_MEMBER

  StageTimes& operator+=(const StageTimes& other) {
#define SKELCD_STAGE_ADD(name, meaning) name += other.name;
    SKELCD_STAGE_TIMES(SKELCD_STAGE_ADD)
#undef SKELCD_STAGE_ADD
    return *this;
  }
};

/// Room in `findings` for one more. A vector doubles as push_back would up to 256 KiB; past that
/// it grows by whole 2 MiB steps at once, so that the skelcd executable puts each larger block on
/// huge pages whole (tools/cli/large_pages.hpp) and many findings — the cloth-ball step's 113,854
/// contacts take 3.6 MB — are first touched in a few huge pages instead of a thousand small ones,
/// the blocks that doubling passes through below 2 MiB included (on this project's VM the first
/// touch of a small page costs about 15 µs: docs/benchmarks.md, "Fewer first touches in an
/// interval").
template <class T>
void room_for_one_more(std::vector<T>& findings) {
  if (findings.size() < findings.capacity()) return;
  constexpr std::size_t kStep = std::size_t{2} << 20;
  const std::size_t bytes = findings.capacity() * sizeof(T);
  if (bytes < (std::size_t{256} << 10)) return;  // push_back doubles
  const std::size_t want = (std::max(2 * bytes, kStep) + kStep - 1) / kStep * kStep;
  findings.reserve(want / sizeof(T));
}

/// A CCD contact in welded numbering. VF: `a` is a welded vertex, `b` a triangle. EE: `a` and `b`
/// are edges (Topology::edges rows). Pairs are canonical: sorted by (kind, a, b).
struct CcdContact {
  enum class Kind : std::uint8_t { vf = 0, ee = 1 };
  Kind kind = Kind::vf;
  std::int32_t a = -1;
  std::int32_t b = -1;
  double toi_lower = 1.0;
  double toi_upper = 1.0;
  /// Same pair (kind, a, b); the time of impact is not compared.
  [[nodiscard]] bool same_pair(const CcdContact& other) const {
    return kind == other.kind && a == other.a && b == other.b;
  }
  /// Canonical order: (kind, a, b).
  [[nodiscard]] bool before(const CcdContact& other) const {
    if (kind != other.kind) return kind < other.kind;
    if (a != other.a) return a < other.a;
    return b < other.b;
  }
  friend bool operator==(const CcdContact&, const CcdContact&) = default;
};

/// A DCD finding: triangles a < b intersect. (Also a candidate triangle pair of a traversal.)
struct TrianglePair {
  std::int32_t a = -1;
  std::int32_t b = -1;
  friend bool operator==(const TrianglePair&, const TrianglePair&) = default;
  friend auto operator<=>(const TrianglePair&, const TrianglePair&) = default;
};

struct FrameResult {
  Counters counters;
  StageTimes times;
  std::vector<CcdContact> contacts;     ///< sorted by (kind, a, b)
  std::vector<TrianglePair> dcd_pairs;  ///< sorted by (a, b)

  /// Empties the vectors (keeping their capacity) and zeroes counters and times.
  void clear() {
    counters = {};
    times = {};
    contacts.clear();
    dcd_pairs.clear();
  }
};

}  // namespace skelcd::culling
