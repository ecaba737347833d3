#pragma once
// The accuracy-versus-time report of `skelcd bench` (docs/bench.md): every method × accuracy run
// over the same samples and intervals, each run's findings compared as a set with those of a
// reference run (`brute` or `bvh` with the `exact` elementary tests), one row per run with its time
// by stage, its work counters and its false negatives / false positives.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ccd/accuracy.hpp"
#include "skinning/motion.hpp"
#include "tools/engine/run_summary.hpp"
#include "tools/engine/runner.hpp"
#include "tools/io/frame_report.hpp"

namespace skelcd::tools {

/// One finding of a run, keyed so that two runs compare as sets of feature ids:
/// {sample, query (0 DCD, 1 CCD), kind (DCD 0; CCD 0 VF, 1 EE), a.part, a.index, a.side, b.part,
/// b.index, b.side} — a DCD pair at sample `sample`, or a CCD contact in [sample, sample + 1].
/// Times of impact are not part of the key.
using FindingKey = std::array<std::int32_t, 9>;

/// Appends the keys of every DCD pair and CCD contact of `report` to `keys` (unsorted).
void append_finding_keys(const FrameReport& report, std::vector<FindingKey>& keys);

/// How a run's findings differ from the reference's.
struct FindingDifference {
  std::int64_t false_negatives = 0;  ///< in the reference, not in the run
  std::int64_t false_positives = 0;  ///< in the run, not in the reference
};

/// Set difference of two sorted, duplicate-free key lists.
/// @pre both sorted ascending without duplicates.
[[nodiscard]] FindingDifference compare_findings(
    std::span<const FindingKey> reference, std::span<const FindingKey> run);

/// Which run judges the others (`--reference`).
enum class ReferenceChoice : std::uint8_t {
  automatic,  ///< brute + exact when it fits the budget, else bvh + exact
  brute,
  bvh,
};

/// "auto" | "brute" | "bvh" → ReferenceChoice; std::nullopt for anything else.
[[nodiscard]] std::optional<ReferenceChoice> parse_reference_choice(std::string_view name);

/// Estimated brute-force work of a run: triangles² × rows (DCD samples + CCD intervals). Measured
/// on the development machine: ~4 ns per unit for CCD with `conservative`, less for DCD.
[[nodiscard]] double brute_cost(std::int64_t triangles, std::int64_t rows);

/// Default budget of brute_cost under which `auto` picks `brute` (about 10 s of brute force).
inline constexpr double kBruteBudget = 2e9;

/// The resolved reference: its method (always with the `exact` accuracy) and why it was chosen.
struct ReferencePick {
  std::string method;
  std::string reason;
};

/// Picks the reference for `choice`: forced, or brute when brute_cost(triangles, rows) <= budget.
[[nodiscard]] ReferencePick pick_reference(
    ReferenceChoice choice,
    std::int64_t triangles,
    std::int64_t rows,
    double budget = kBruteBudget);

struct BenchOptions {
  /// Methods in table order; empty: every method of culling::method_names(), then `rvbc` and
  /// `dynamic` when `radial_view` is true, without `brute` when it is over the budget.
  std::vector<std::string> methods;
  /// Accuracies in table order; empty: exact, conservative, fast.
  std::vector<ccd::Accuracy> accuracies;
  /// Samples, queries and contact distance shared by every run; method and accuracy are set per
  /// run. Must have min_separation 0 (the exact reference supports only touching).
  RunOptions run;
  ReferenceChoice reference = ReferenceChoice::automatic;
  double brute_budget = kBruteBudget;
  /// The motion is a rig's: the default method list includes `rvbc` and `dynamic`.
  bool radial_view = false;
  /// Called before each run with its options (method and accuracy set), to add what the method
  /// needs beyond the mesh (the radial-view extension and bone-pose hook).
  std::function<void(RunOptions&)> prepare;
  /// Builds the method of a run; returning null (or an empty factory) means make_method. Tests
  /// use it to inject a weakened method.
  std::function<MethodFactory(const std::string& method, ccd::Accuracy accuracy)> factory;
  /// Show a progress line per run on stderr (tools::Progress; only on a terminal).
  bool progress = false;
};

/// One row of the report: one method at one accuracy.
struct BenchRow {
  std::string method;
  ccd::Accuracy accuracy = ccd::Accuracy::exact;
  bool reference = false;  ///< this run is the reference
  /// Times per interval by stage, BV tests, candidate pairs, DCD pairs and VF/EE contacts.
  RunSummary summary;
  std::int64_t elementary_tests = 0;  ///< VF + EE + triangle-triangle tests, summed
  std::int64_t contacts = 0;          ///< DCD pairs + VF + EE contacts, summed
  std::int64_t false_negatives = 0;
  std::int64_t false_positives = 0;
};

struct BenchReport {
  std::string motion;  ///< the motion's name (clip)
  std::int64_t triangles = 0;
  RunPlan plan;
  QuerySet query = QuerySet::both;
  ReferencePick reference;
  std::int64_t reference_contacts = 0;
  std::vector<BenchRow> rows;
  /// Methods left out of the default list, one sentence each (brute over the budget).
  std::vector<std::string> notes;
};

/// Validates the method and accuracy lists against the known names before any work.
/// @throws InvalidInput naming the unknown method (listing the known ones).
void validate_methods(std::span<const std::string> methods, bool radial_view);

/// Runs the reference, then every method × accuracy (reusing the reference run for its own row).
/// @throws InvalidInput for an unknown method, a bad frame range, min_separation != 0, or a
///   non-finite posed position (as ClipRunner does).
[[nodiscard]] BenchReport run_bench(const skinning::Motion& motion, const BenchOptions& options);

/// The aligned text table (one line per row, the reference marked with `*`).
void print_bench_table(std::ostream& out, const BenchReport& report);

/// CSV header: method,accuracy,ms_per_interval,bv_tests,candidate_pairs,contacts,false_negatives,
/// false_positives, then the stage columns (skin_ms … other_ms), elementary_tests, dcd_pairs,
/// ccd_vf, ccd_ee, reference.
[[nodiscard]] std::string bench_csv(const BenchReport& report);

/// One object: model-independent run facts and a `rows` array (same fields as the CSV).
[[nodiscard]] nlohmann::json bench_json(const BenchReport& report);

/// Writes the time-against-missed-collisions PNG (pngcairo): one labelled point per row, ms per
/// interval (log scale) against false negatives.
/// @throws IoError naming `path` when it cannot be written.
void write_bench_plot(
    const std::filesystem::path& path, const BenchReport& report, const std::string& title);

/// An output file written whole or not at all: the constructor creates `<path>.tmp-<pid>` beside
/// `path` (so an unwritable destination is refused before any work), commit() renames it over
/// `path`; destroyed uncommitted, the temporary file is removed.
class PendingOutput {
 public:
  /// @throws IoError naming `path` when the temporary file cannot be created.
  explicit PendingOutput(std::filesystem::path path);
  ~PendingOutput();
  PendingOutput(const PendingOutput&) = delete;
  PendingOutput& operator=(const PendingOutput&) = delete;

  [[nodiscard]] const std::filesystem::path& temporary() const { return temporary_; }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  /// Replaces the temporary file's content with `text`.
  /// @throws IoError naming the destination.
  void write(std::string_view text) const;
  /// Renames the temporary file to the destination. @throws IoError naming it.
  void commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path temporary_;
  bool committed_ = false;
};

}  // namespace skelcd::tools
