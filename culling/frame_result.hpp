#pragma once
// What one interval (CCD) or one instant (DCD) produces: contacts in welded numbering, counters and
// stage timings — the same for every culling method so methods compare on equal terms.

#include <compare>
#include <cstdint>
#include <vector>

namespace skelcd::culling {

/// Work counters of one interval; every method fills the ones it uses and leaves the rest 0.
struct Counters {
  std::int64_t atomic_clusters = 0;
  std::int64_t mega_clusters = 0;
  std::int64_t h_minus = 0;      ///< triangles in H⁻ (radial-view methods)
  std::int64_t h_uncertain = 0;  ///< triangles in Hᵘ (radial-view methods)
  std::int64_t bv_tests = 0;     ///< bounding-volume overlap tests
  std::int64_t candidate_pairs = 0;  ///< candidate triangle pairs reaching the feature stage
  std::int64_t vf_tests = 0;     ///< vertex-face elementary tests
  std::int64_t ee_tests = 0;     ///< edge-edge elementary tests
  std::int64_t vf_contacts = 0;
  std::int64_t ee_contacts = 0;
  std::int64_t tt_tests = 0;     ///< triangle-triangle DCD tests
  std::int64_t dcd_pairs = 0;    ///< intersecting triangle pairs found by DCD
  /// Feature-pair volume tests (VF: vertex vs face, EE: edge vs edge) before the elementary
  /// tests; a cheap filter, counted apart from the hierarchy's bv_tests.
  std::int64_t feature_bv_tests = 0;
};

/// Microseconds spent per stage in one interval.
struct StageTimes {
  double skin_us = 0;
  double refit_us = 0;
  double classify_us = 0;
  double merge_us = 0;
  double traverse_us = 0;
  double elementary_us = 0;
};

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
