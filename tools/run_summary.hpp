#pragma once
// Totals of a run computed from its /frames rows — the same numbers for `check` (as it runs) and
// `inspect` (from a log, complete or partial).

#include <cstdint>
#include <span>
#include <vector>

#include <nlohmann/json.hpp>

#include "tools/frame_report.hpp"

namespace skelcd::tools {

struct RunSummary {
  std::int64_t rows = 0;
  std::int32_t samples = 0;    ///< samples checked (DCD rows; for CCD only, intervals + 1)
  std::int32_t intervals = 0;  ///< CCD rows
  std::int64_t dcd_pairs = 0;  ///< summed over the run
  std::int64_t ccd_vf = 0;
  std::int64_t ccd_ee = 0;
  /// Frames f with a finding keyed to f: a DCD pair at sample f or a CCD contact in [f, f+1].
  std::int32_t frames_with_contacts = 0;
  std::int32_t frames_with_interpenetration = 0;  ///< samples with at least one DCD pair
  std::int32_t intervals_with_contacts = 0;       ///< intervals with at least one CCD contact
  std::int64_t max_candidate_pairs = 0;           ///< over all rows
  std::int64_t bv_tests = 0;                      ///< summed
  std::int64_t candidate_pairs = 0;               ///< summed
  double total_ms = 0;  ///< sum of the rows' wall times
  /// total_ms / steps, where a step is an interval (with its end sample's DCD when both queries
  /// ran) or, for --query dcd, a sample.
  double ms_per_interval = 0;
  /// Per-stage ms per step, same denominator; `other` is what no stage accounts for.
  double skin_ms = 0, refit_ms = 0, classify_ms = 0, merge_ms = 0, traverse_ms = 0,
         elementary_ms = 0, other_ms = 0;
  /// Rows with the most findings (DCD pairs + CCD contacts), most first, ties by time; at most
  /// the `worst` count asked for, rows without findings left out.
  std::vector<FrameRow> worst;
};

[[nodiscard]] RunSummary summarize(std::span<const FrameRow> rows, std::size_t worst = 5);

/// Findings of one row: DCD pairs + VF + EE contacts.
[[nodiscard]] std::int64_t findings(const FrameRow& row);

/// {"ms_per_interval", "skin", "refit", …} → per-stage ms object used by `check --json`.
[[nodiscard]] nlohmann::json stages_json(const RunSummary& summary);

}  // namespace skelcd::tools
