#pragma once
// The JSON of a check: what `check --json` prints (one object per clip, with its events and its
// stage times), what a scene's --json and `bench --json` reuse, and what skelcd.check and
// skelcd.read_log return (docs/python.md).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tools/engine/run_summary.hpp"
#include "tools/io/event_record.hpp"

namespace skelcd::tools {

/// {"ms_per_interval", "skin", "refit", …} → per-stage ms object used by `check --json`.
[[nodiscard]] nlohmann::json stages_json(const RunSummary& summary);

/// {"topology", "segmentation", "baseline", "methods", "total"}: `check --json`'s setup_ms.
[[nodiscard]] nlohmann::json setup_json(const SetupTimes& setup);

/// The events of `check --json`: root events, each with the ids merged into it.
[[nodiscard]] nlohmann::json events_json(
    const std::vector<EventRecord>& events, const std::vector<std::string>& part_names);

/// The object `skelcd check --json` prints for one clip; skelcd.check and skelcd.read_log return
/// the same keys.
[[nodiscard]] nlohmann::json summary_json(
    const RunIdentity& id, const RunSummary& summary, const RunLabels& labels);

}  // namespace skelcd::tools
