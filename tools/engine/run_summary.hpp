#pragma once
// Totals of a run computed from its /frames rows — the same numbers for `check` (as it runs) and
// `inspect` (from a log, complete or partial).

#include <cstdint>
#include <span>
#include <vector>

#include "tools/engine/events.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

struct RunSummary {
  std::int64_t rows = 0;
  std::int32_t samples = 0;    ///< samples checked (DCD rows; for CCD only, intervals + 1)
  std::int32_t intervals = 0;  ///< CCD rows
  std::int64_t dcd_pairs = 0;  ///< summed over the run
  std::int64_t ccd_vf = 0;
  std::int64_t ccd_ee = 0;
  /// Labelled findings (docs/events.md), summed: new (the events'), the baseline's, allowed. In
  /// a log written before events, every finding counts as new.
  std::int64_t new_dcd_pairs = 0;
  std::int64_t new_ccd_contacts = 0;
  std::int64_t baseline_dcd_pairs = 0;
  std::int64_t baseline_ccd_contacts = 0;
  std::int64_t allowed_dcd_pairs = 0;
  std::int64_t allowed_ccd_contacts = 0;
  /// Frames f with a new finding keyed to f: a DCD pair at sample f or a CCD contact in [f, f+1].
  std::int32_t frames_with_contacts = 0;
  std::int32_t frames_with_interpenetration = 0;  ///< samples with at least one new DCD pair
  std::int32_t intervals_with_contacts = 0;       ///< intervals with at least one new CCD contact
  std::int64_t max_candidate_pairs = 0;           ///< over all rows
  std::int64_t bv_tests = 0;                      ///< summed
  std::int64_t candidate_pairs = 0;               ///< summed
  double total_ms = 0;                            ///< sum of the rows' wall times
  /// total_ms / steps, where a step is an interval (with its end sample's DCD when both queries
  /// ran) or, for --query dcd, a sample.
  double ms_per_interval = 0;
  /// Per-stage ms per step, same denominator; `other` is what no stage accounts for.
  double skin_ms = 0, refit_ms = 0, classify_ms = 0, merge_ms = 0, traverse_ms = 0,
         elementary_ms = 0, other_ms = 0;
  /// Rows with the most new findings (DCD pairs + CCD contacts), most first, ties by time; at most
  /// the `worst` count asked for, rows without findings left out.
  std::vector<FrameRow> worst;
};

[[nodiscard]] RunSummary summarize(std::span<const FrameRow> rows, std::size_t worst = 5);

/// Findings of one row: DCD pairs + VF + EE contacts.
[[nodiscard]] std::int64_t findings(const FrameRow& row);
/// The row's new findings: those neither in the baseline nor allowed; all of them when the row is
/// not labelled (a log written before events).
[[nodiscard]] std::int64_t new_findings(const FrameRow& row);
/// The row's new DCD pairs and new CCD contacts, likewise.
[[nodiscard]] std::int64_t new_dcd_pairs(const FrameRow& row);
[[nodiscard]] std::int64_t new_ccd_contacts(const FrameRow& row);

/// What a run was: the identity fields of `check --json` (and of skelcd.check / read_log).
struct RunIdentity {
  std::string model;
  std::string clip;
  double fps = 0;
  std::int32_t first_sample = 0;
  std::int32_t last_sample = 0;
  std::string method;
  std::string accuracy;
  std::string query;
  std::string log;  ///< empty: no log
};

/// What the findings were labelled against, and the events (docs/events.md).
struct RunLabels {
  std::string
      baseline;  ///< describe(BaselineSpec); empty: not labelled (a log written before events)
  std::int32_t baseline_slack = 0;
  std::vector<std::string> allow;
  bool allow_adjacent_bones = false;
  std::vector<EventRecord> events;  ///< every record, merged ones included
  bool events_recorded = true;      ///< false: no event data (a log before events, or cut short)
  std::vector<std::string> part_names;
};

/// The events a user reads: those that did not run into an older one (whose records the older
/// one's include), by id.
[[nodiscard]] std::vector<const EventRecord*> root_events(const std::vector<EventRecord>& events);

/// Wall times, in ms, of what a check does before its first row (after the model is loaded: its
/// import is the caller's). In a parallel run the baseline's DCD runs on a thread of its own beside
/// the segmentation and the methods' builds, so the parts may add up to more than `total`.
struct SetupTimes {
  double topology = 0;      ///< welding the mesh (shared by the segmentation, baseline, methods);
                            ///< in a serial run also its FeatureTopology (baseline and methods)
  double segmentation = 0;  ///< the radial view's segmentation, computed or read (0: none)
  double baseline = 0;      ///< the baseline's findings (its DCD)
  double methods = 0;       ///< building the runner: every worker's culling method
  double total = 0;         ///< check_model's start to its first row (log creation included)
};

}  // namespace skelcd::tools
