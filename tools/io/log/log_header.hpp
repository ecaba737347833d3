#pragma once
// The root attributes of a skelcd log: what was checked, how, and when (docs/log-format.md).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace skelcd::tools {

/// Value of the root attribute `format` that marks a file as a skelcd log.
inline constexpr const char* kLogFormatName = "skelcd-log";
/// Version of the schema written by this build; readers accept versions <= this.
/// 2: finding labels, /events, the baseline attributes and /checksums over every stored column
/// (a version-1 reader checksums only the columns it knows and would call a version-2 log
/// damaged, so it refuses it by its version instead).
inline constexpr std::int32_t kLogFormatVersion = 2;

/// Where one connected component of the mesh went under `auto` (culling::ComponentRoute): stored
/// as the /routes group, one row per component.
struct LogRoute {
  std::int32_t component = -1;  ///< connected component (welded mesh), in component order
  std::int32_t part = -1;       ///< file part of its first triangle (index into /parts)
  bool closed = false;          ///< no boundary and no non-manifold edge
  std::int32_t triangles = 0;
  std::string method;  ///< the method that tested its pairs
  friend bool operator==(const LogRoute&, const LogRoute&) = default;
};

/// One check of a scene (docs/scenes.md): stored as the /checks group, one row per check; the
/// /frame_check dataset gives each /frames row's check.
struct LogCheck {
  std::string name;  ///< "self body", "pair body cape"
  std::string object_a;
  std::string object_b;  ///< empty for a self check
  std::string query;     ///< "dcd" | "ccd" | "both"
  std::string method;
  std::string accuracy;
  friend bool operator==(const LogCheck&, const LogCheck&) = default;
};

struct LogHeader {
  std::int32_t format_version = kLogFormatVersion;
  std::string skelcd_version;
  std::string command_line;
  std::string input_path;
  std::string input_hash;  ///< "fnv1a64:<16 hex digits>" of the input file's bytes
  std::string clip;
  std::string method;
  std::string accuracy;
  std::string query;            ///< "dcd" | "ccd" | "both"
  double fps = 0;               ///< sampling rate of the clip (samples per second)
  double min_separation = 0;    ///< contact distance, coordinate units
  std::optional<double> gamma;  ///< radial-view merge parameter γ, only when the method uses it
  std::optional<double> theta;  ///< cone angle θ (radians), only when the method uses it
  std::optional<std::int64_t> seed;  ///< `dynamic`'s seed (`--seed`), only when the method uses it
  /// Where rvbc/dynamic took their segmentation from (a SEG.h5 path, "computed (rig weights)", …);
  /// empty (and absent) when no radial-view method ran.
  std::string segmentation;
  std::string start_time;         ///< ISO 8601 UTC, e.g. 2026-01-31T12:00:00Z
  std::int32_t first_sample = 0;  ///< samples first_sample … last_sample were asked for
  std::int32_t last_sample = 0;
  std::int64_t planned_rows = 0;  ///< rows /frames will hold when the run completes
  std::int64_t num_vertices = 0;  ///< file vertices of the mesh
  std::int64_t num_triangles = 0;
  std::vector<std::string> part_names;  ///< stored as the /parts dataset
  std::vector<LogRoute> routes;  ///< the /routes group; empty (and absent) unless method is auto
  /// The /checks group and /frame_check dataset; empty (and absent) unless the log is a scene's.
  std::vector<LogCheck> checks;
  /// What the findings were compared with (docs/events.md): "rest pose", "sample 12", "none",
  /// "log PATH"; empty in a log written before events existed (its findings are unlabelled).
  std::string baseline;
  std::int32_t baseline_slack = 0;    ///< rings of triangles a baseline region may slide by
  std::vector<std::string> allow;     ///< `--allow` rules as given ("PART_A:PART_B")
  bool allow_adjacent_bones = false;  ///< `--allow-adjacent-bones`
  bool complete = false;              ///< set when the run finished; false in a log of a killed run
};

/// The current time as ISO 8601 UTC with seconds ("2026-01-31T12:00:00Z").
[[nodiscard]] std::string iso8601_utc_now();

/// What every log says of its run, whoever writes it (a clip's check or a scene): the input, the
/// command, the samples asked for, the planned rows and the mesh checked.
struct LogRunFacts {
  std::string input_path;
  std::string input_hash;  ///< "fnv1a64:<16 hex digits>" (file_hash.hpp)
  std::string command_line;
  std::int32_t first_sample = 0;
  std::int32_t last_sample = 0;
  std::int64_t planned_rows = 0;
  std::int64_t num_vertices = 0;
  std::int64_t num_triangles = 0;
  std::vector<std::string> part_names;
};

/// The one place a log header starts: this build's version, the start time (now) and `facts`;
/// the caller fills what its kind of run adds (clip, method, accuracy, query, routes, baseline…).
[[nodiscard]] LogHeader log_header_base(LogRunFacts facts);

}  // namespace skelcd::tools
