#pragma once
// Small pieces every command uses: JSON output, a progress line on a terminal
// (report/progress.hpp), rate options, path checks.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "tools/report/progress.hpp"

namespace skelcd::tools {

/// Prints `object` to stdout as one JSON document followed by a newline.
void print_json(const nlohmann::json& object);

/// Adds a sampling-rate option (`names`, e.g. "--fps" or "--rate,--fps") that stores a rate in
/// samples/s into `rate`. Leaving it out keeps `rate` as it is (0: the model's default); giving a
/// value that is not finite and > 0 (0 included) is refused: InvalidInput "--fps 0: expected a
/// rate > 0 (samples/s)".
CLI::Option* add_rate_option(
    CLI::App& command, const std::string& names, double& rate, const std::string& help);

/// The help of a rate option that samples a clip, saying its default: the clip's frame rate
/// (skinning::ClipSummary::rate_hz), else 30.
inline constexpr const char* kClipRateHelp =
    "samples per second (default: the clip's frame rate, else 30; `skelcd info` shows it)";

/// Throws IoError "<path>: no such file" unless `path` exists.
void require_exists(const std::filesystem::path& path);

}  // namespace skelcd::tools
