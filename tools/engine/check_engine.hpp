#pragma once
// The check of one clip as a library call: what `skelcd check` does for one model and clip —
// motion, radial-view setup, runner, log — without a command line, JSON or a terminal. The CLI,
// and the Python module, call it; rows reach the caller as they complete.

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "ccd/accuracy.hpp"
#include "skinning/load.hpp"
#include "tools/engine/events.hpp"
#include "tools/engine/radial_view_setup.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/engine/runner.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

/// What to check, and how. The defaults are `skelcd check`'s, but for `threads` (1 here, all
/// cores on the command line).
struct CheckRequest {
  std::string clip;   ///< empty: the model's first clip (its bind pose when it has none)
  double fps = 0;     ///< samples per second; 0: the clip's frame rate, else 30
  FrameRange frames;  ///< samples first … last
  std::string method = "auto";
  ccd::Accuracy accuracy = ccd::Accuracy::conservative;
  QuerySet query = QuerySet::both;
  double min_separation = 0;  ///< contact distance, model units
  std::int32_t threads = 1;   ///< 0: all cores
  /// With both queries, each DCD after the first updates the previous one from the interval's
  /// CCD contacts (RunOptions::incremental_dcd); false: full DCD at every sample.
  bool incremental_dcd = true;
  /// An interval holding the last held pose gets that interval's row
  /// (RunOptions::reuse_static_intervals); false: every interval is queried (`--no-reuse`).
  bool reuse_static_intervals = true;
  /// Rigid rows for a method that takes them (RunOptions::rigid_rows); false: `--no-rigid-rows`.
  bool rigid_rows = true;
  RadialViewArguments radial_view;  ///< γ, seed, segmentation file of rvbc/dynamic/auto
  /// What findings are compared with (docs/events.md): the rig's rest pose by default.
  BaselineSpec baseline;
  /// Rings of triangles a baseline region may slide by and still be the baseline's.
  std::int32_t baseline_slack = kDefaultBaselineSlack;
  /// Pairs of parts or bones whose findings are allowed (counted apart).
  Allowances allow;
  /// Where to write the HDF5 log (docs/log-format.md); empty: no log.
  std::string log_path;
  /// For the log header: the MODEL argument as the user wrote it (empty: the model's path) and
  /// the command line that asked for the check.
  std::string input_path;
  std::string command_line;
  /// When set, elementary tests count into it as they finish (a progress line inside one query).
  std::atomic<std::int64_t>* tests_done = nullptr;
  /// Called once the check is planned, before the first row (a progress line learns how many
  /// rows to expect), after the log is created — except in a parallel run whose baseline is still
  /// running: it creates the log at its first row (and may still refuse the baseline then).
  std::function<void(const RunPlan&)> on_plan;
};

/// What a check found and how it ran.
struct CheckOutcome {
  std::string clip;    ///< the motion's name
  double fps = 0;      ///< samples per second it was sampled at
  std::string method;  ///< the method that ran
  RunPlan plan;
  RadialViewSetup radial_view;
  std::vector<FrameRow> rows;  ///< every row, in order
  RunSummary summary;
  std::string baseline;             ///< describe(request.baseline)
  std::int64_t baseline_pairs = 0;  ///< intersecting pairs (and contacts) of the baseline
  std::vector<EventRecord> events;  ///< the new findings' events, by id
  SetupTimes setup;                 ///< where the time before the first row went
};

/// Called with each labelled row of check_model, in order; the row is only lent.
using RowCallback = std::function<void(const FrameReport&)>;

/// Checks one clip of `model`: one FrameReport per DCD sample and CCD interval, in order, passed
/// to `on_row` (after it reached the log, when there is one). Everything that can be refused — the
/// clip, the rate, the frame range, the method, the segmentation — is refused before the log is
/// created.
/// @throws InvalidInput / IoError with one-line messages naming the model, clip or file.
[[nodiscard]] CheckOutcome check_model(
    const skinning::LoadedModel& model,
    const CheckRequest& request,
    const RowCallback& on_row = {});

/// The identity fields of the check's summary (summary_json): the model's path, the clip, rate,
/// samples, method, accuracy, query and the log.
[[nodiscard]] RunIdentity check_identity(
    const skinning::LoadedModel& model, const CheckRequest& request, const CheckOutcome& outcome);
/// The baseline, allowances and events of the check, for summary_json.
[[nodiscard]] RunLabels check_labels(
    const skinning::LoadedModel& model, const CheckRequest& request, const CheckOutcome& outcome);

/// `text` as part of a file name: letters, digits, '-', '_' and '.' kept, anything else '_', no
/// leading dot; "model" when nothing is left.
[[nodiscard]] std::string file_name_part(const std::string& text);

/// The name (without ".h5") of a batch's log of `clip` of `model_arg`: the model file's stem (a
/// frame sequence's folder, a generator spec as written), then "-CLIP" when there is one. The
/// command line's batch and `skelcd.batch` name logs so.
[[nodiscard]] std::string batch_log_name(const std::string& model_arg, const std::string& clip);

/// Every method name a check accepts (culling's and radial view's), in `bench` order.
[[nodiscard]] std::vector<std::string> check_method_names();

}  // namespace skelcd::tools
