#pragma once
// What the runner produces for one sample (DCD) or one interval (CCD), in the file's own numbering:
// the row of the log's /frames table plus that row's contacts and intersecting triangle pairs.
// The HDF5 log stores exactly these records (docs/log-format.md).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "culling/frame_result.hpp"

namespace skelcd::tools {

/// Which query a row answers: DCD at one sample instant or CCD over the interval between two
/// samples.
enum class QueryKind : std::uint8_t { dcd = 0, ccd = 1 };

/// The queries a run asks for (`--query`).
enum class QuerySet : std::uint8_t { dcd, ccd, both };

[[nodiscard]] std::string_view to_string(QueryKind kind);
[[nodiscard]] std::string_view to_string(QuerySet queries);
/// "dcd" | "ccd" | "both" → QuerySet; std::nullopt for anything else.
[[nodiscard]] std::optional<QuerySet> parse_query_set(std::string_view name);

/// A mesh feature in the file's own numbering.
/// - a vertex: `index` is the vertex's index within mesh part `part`, `side` = -1;
/// - a triangle: `index` is the triangle's index within part `part`, `side` = -1;
/// - an edge: side `side` (0, 1, 2: from corner side to corner (side + 1) % 3) of the triangle
///   (`part`, `index`).
struct FeatureId {
  std::int32_t part = -1;
  std::int32_t index = -1;
  std::int8_t side = -1;
  friend bool operator==(const FeatureId&, const FeatureId&) = default;
};

/// One row of /frames.
struct FrameRow {
  /// DCD: the sample tested. CCD: the first sample of the interval [sample, sample + 1].
  std::int32_t sample = 0;
  double t0 = 0;  ///< seconds; DCD: the sample's time (t1 == t0)
  double t1 = 0;
  QueryKind kind = QueryKind::dcd;
  culling::Counters counters;
  /// Microseconds per stage. skin_us is the time to pose the samples this row was the first to
  /// need (positions, finiteness check, welding); the rest come from the culling method.
  culling::StageTimes times;
  double total_us = 0;  ///< wall time of the whole row, skinning included
};

/// What a finding is against the check's baseline and the user's allowances (docs/events.md):
/// a value >= 0 is the id of the new event it belongs to (the log's /events row).
inline constexpr std::int32_t kLabelBaseline = -1;  ///< the rig already had it (the baseline)
inline constexpr std::int32_t kLabelAllowed = -2;   ///< between parts or bones the user allowed
/// Not labelled: a log written before events existed (its rows read so), or a runner's raw rows.
inline constexpr std::int32_t kLabelNone = -3;

/// One row of /contacts: a CCD contact. VF: `a` is a vertex, `b` a triangle. EE: both are edges.
struct ContactRow {
  std::int32_t frame = 0;  ///< first sample of the interval
  culling::CcdContact::Kind kind = culling::CcdContact::Kind::vf;
  FeatureId a;
  FeatureId b;
  double toi_lower = 1;  ///< fraction of the interval, in [0, 1]
  double toi_upper = 1;
  std::int32_t label = kLabelNone;  ///< event id, kLabelBaseline, kLabelAllowed or kLabelNone
  friend bool operator==(const ContactRow&, const ContactRow&) = default;
};

/// One row of /dcd_pairs: two triangles intersecting at sample `frame`.
struct DcdPairRow {
  std::int32_t frame = 0;
  FeatureId a;  ///< a triangle (side -1)
  FeatureId b;
  std::int32_t label = kLabelNone;  ///< event id, kLabelBaseline, kLabelAllowed or kLabelNone
  friend bool operator==(const DcdPairRow&, const DcdPairRow&) = default;
};

/// Everything one sample or interval produced.
struct FrameReport {
  FrameRow row;
  std::vector<ContactRow> contacts;
  std::vector<DcdPairRow> dcd_pairs;
};

}  // namespace skelcd::tools
